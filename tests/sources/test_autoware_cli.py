"""`evoeye export autoware` and `evoeye import autoware` from the shell."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.cli.errors import ExitCode


def test_export_then_import_from_the_shell(sim_runs, tmp_path: Path) -> None:
    runner = CliRunner()
    bags = tmp_path / "bags"
    result = runner.invoke(app, ["export", "autoware", "--out", str(bags), "--rates",
                                 "lossless", "--root", str(sim_runs.root.path)])
    assert result.exit_code == 0, result.output
    exported = sorted(p.name for p in bags.iterdir())
    assert exported == sorted(sim_runs.logs)
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(b"not a bag")
    root = tmp_path / "data"
    result = runner.invoke(app, ["import", "autoware", str(bags), str(broken),
                                 "--root", str(root)])
    assert result.exit_code == ExitCode.PARTIAL, result.output
    assert "2 recordings converted, 2 runs ingested" in result.stdout
    refused = [line for line in result.output.splitlines() if line.startswith("refused")]
    assert len(refused) == 1  # one line, however long: not wrapped for a file or a pipe
    assert refused[0].startswith(f"refused {broken}: (bag): unreadable bag (")
    assert refused[0].endswith(")")
    result = runner.invoke(app, ["import", "autoware", str(bags), "--root", str(root)])
    assert result.exit_code == 0 and "0 runs ingested, 2 already in the warehouse" in \
        result.stdout


def test_export_needs_a_monitor_or_a_subcommand(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["export", "--out", str(tmp_path / "m.onnx")])
    assert result.exit_code == ExitCode.USER_ERROR
    assert "needs --monitor and --out" in result.output


def test_a_bad_mapping_file_is_one_line(tmp_path: Path) -> None:
    mapping = tmp_path / "map.toml"
    mapping.write_text('[topics]\nodometri = "/x"\n')
    result = CliRunner().invoke(app, ["import", "autoware", str(tmp_path), "--mapping",
                                      str(mapping), "--root", str(tmp_path / "d")])
    assert result.exit_code == ExitCode.USER_ERROR
    assert "unknown keys ['odometri']" in result.output


def test_a_mapping_file_overrides_topics_vehicle_and_clock(tmp_path: Path) -> None:
    from evoeye.sources.autoware.config import load_mapping

    mapping = tmp_path / "map.toml"
    mapping.write_text('[topics]\nodometry = "/odom"\ncollision = ""\n'
                       '[planning_factors]\n"/f/stop" = "yield"\n'
                       '[vehicle]\nlength_m = 4.0\nrear_overhang_m = 0.5\n'
                       '[clock]\nmax_gap_s = 1.0\n')
    m = load_mapping(mapping)
    assert m.topics.odometry == "/odom" and m.topics.collision == ""
    assert m.roles()["/odom"] == "odometry" and "" not in m.roles()
    assert m.planning_factors == {"/f/stop": "yield"} and m.roles()["/f/stop"] == "factor"
    assert m.vehicle.centre_ahead_m == 1.5 and m.max_gap_s == 1.0
