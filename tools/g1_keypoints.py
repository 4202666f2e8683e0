"""The G1's default keypoint set, upper body then lower, as `data/robots/g1_29dof/robot.toml`
(`[keypoints.default]`) lists it: the order of a trace's `keypoints_w` and of the tools
that score keypoints outside the Rust code."""

DEFAULT_KEYPOINT_BODIES = (
    "torso_link",
    "left_shoulder_roll_link",
    "right_shoulder_roll_link",
    "left_elbow_link",
    "right_elbow_link",
    "left_wrist_yaw_link",
    "right_wrist_yaw_link",
    "left_hip_roll_link",
    "right_hip_roll_link",
    "left_knee_link",
    "right_knee_link",
    "left_ankle_roll_link",
    "right_ankle_roll_link",
)
