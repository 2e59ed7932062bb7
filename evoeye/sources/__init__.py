"""Other stacks' recordings, normalised once at the boundary into evoeye runs.

Each adapter turns a foreign log into the channel messages of an evoeye run log (the
`evoeye.store.records.RunSource` contract: one message per topic per 20 Hz frame, world frame,
SI units, evoeye's reference points and grids), so ingest, features, training, replay and the
runtime monitor work on it unchanged. `autoware/`: Autoware (ROS 2) rosbag2 bags.
"""
