"""Episode ⇄ MCAP: one log file per run, channels bound to the schemas in `schemas/mcap/`."""

from evoeye.log.channels import CHANNELS, TOPICS, Topics
from evoeye.log.reader import LogError, RunLog, read_run
from evoeye.log.writer import write_episode

__all__ = ["CHANNELS", "TOPICS", "LogError", "RunLog", "Topics", "read_run", "write_episode"]
