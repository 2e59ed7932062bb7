"""Autoware (ROS 2) rosbag2 bags ⇄ evoeye runs, and the frames `evoeye watch` scores live.

    config     topics per role, vehicle and clock; a TOML mapping file overrides them
    typestore  ROS 2 Humble's types plus the vendored Autoware ones (schemas/external/autoware)
    convert    one message → evoeye's conventions (body centre, world-frame twists, yaw, ids)
    grids      predicted paths and trajectories resampled by time onto evoeye's grids
    labels     ground truth and the collision label from the bag's simulation topics
    frames     messages in receive order → 20 Hz frames with each message's age
    bag        a bag → an evoeye run (metadata and frames); importer: into the warehouse
    export     an evoeye run log → an Autoware bag
    follow     a bag being recorded, read as it grows (evoeye watch)
"""
