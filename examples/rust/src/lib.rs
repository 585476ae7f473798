//! What the example programs share: the generated robot types and the gain profiles.

/// The types of robot/joint_state, robot/command and robot/set_gains (build.rs).
pub mod msg {
    include!(concat!(env!("OUT_DIR"), "/robot.rs"));
}

/// Joints of the demo arm.
pub const JOINTS: usize = 7;

/// A gain profile by name: (kp in Nm/rad, kd in Nm s/rad per joint), those of supervisor.py.
pub fn profile(name: &str) -> Option<([f64; JOINTS], [f64; JOINTS])> {
    match name {
        "soft" => Some((
            [50.0, 50.0, 30.0, 25.0, 12.0, 8.0, 4.0],
            [10.0, 10.0, 6.0, 5.0, 2.5, 1.6, 0.8],
        )),
        "stiff" => Some((
            [250.0, 250.0, 160.0, 120.0, 60.0, 40.0, 20.0],
            [22.0, 22.0, 14.0, 11.0, 5.5, 3.6, 1.8],
        )),
        "unsafe" => Some((
            [5000.0, 250.0, 160.0, 120.0, 60.0, 40.0, 20.0],
            [22.0, 22.0, 14.0, 11.0, 5.5, 3.6, 1.8],
        )),
        _ => None,
    }
}
