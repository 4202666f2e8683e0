//! The `unitree_hg` codec agrees with Unitree's own Python SDK (unitree_sdk2_python on
//! PyPI's `cyclonedds` 11.0.1): the same `LowCmd_` and `LowState_` serialize to the same
//! CDR bytes, carry the same checksum (the SDK's `CRC().Crc`), and the SDK's bytes decode
//! to the same message here. Skipped, saying so, when `../shared/reference` (the SDK) or
//! Python's `cyclonedds` is absent; never in CI.

use std::process::Command;
use thorarena::dds::unitree_hg::MODE_MACHINE_G1_29DOF;
use thorarena::dds::{LowCmd, LowState, MotorCmd};
mod prereq;

/// The messages the SDK builds below, built here: values exact in float32.
fn messages() -> (LowCmd, LowState) {
    let mut cmd = LowCmd {
        mode_machine: MODE_MACHINE_G1_29DOF,
        ..Default::default()
    };
    for (i, m) in cmd.motor_cmd.iter_mut().enumerate().take(29) {
        *m = MotorCmd {
            mode: 1,
            q: i as f32 / 8.0,
            dq: -0.5,
            tau: 0.25,
            kp: 100.0 + i as f32,
            kd: 2.5,
            reserve: i as u32,
        };
    }
    cmd.crc = cmd.crc_of();
    let mut state = LowState {
        mode_machine: MODE_MACHINE_G1_29DOF,
        tick: 42,
        ..Default::default()
    };
    state.imu_state.quaternion = [1.0, 0.0, 0.0, 0.0];
    state.imu_state.temperature = -3;
    state.motor_state[28].q = 0.5;
    state.motor_state[28].temperature = [40, 41];
    state.wireless_remote[2] = 0x10;
    state.crc = state.crc_of();
    (cmd, state)
}

const SDK_SCRIPT: &str = r#"
from unitree_sdk2py.idl.default import unitree_hg_msg_dds__LowCmd_, unitree_hg_msg_dds__LowState_
from unitree_sdk2py.utils.crc import CRC
c = unitree_hg_msg_dds__LowCmd_()
c.mode_machine = 5
for i in range(29):
    m = c.motor_cmd[i]
    m.mode, m.q, m.dq, m.tau, m.kp, m.kd, m.reserve = 1, i / 8, -0.5, 0.25, 100.0 + i, 2.5, i
c.crc = CRC().Crc(c)
s = unitree_hg_msg_dds__LowState_()
s.mode_machine = 5
s.tick = 42
s.imu_state.quaternion = [1.0, 0.0, 0.0, 0.0]
s.imu_state.temperature = -3
s.motor_state[28].q = 0.5
s.motor_state[28].temperature = [40, 41]
s.wireless_remote[2] = 0x10
s.crc = CRC().Crc(s)
print(c.serialize().hex())
print(c.crc)
print(s.serialize().hex())
print(s.crc)
"#;

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex(text: &str) -> Vec<u8> {
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
        .collect()
}

#[test]
fn the_codec_writes_reads_and_checksums_as_unitrees_python_sdk() {
    const TEST: &str = "dds_codec::python_sdk";
    let Some(sdk) = prereq::unitree_sdk(TEST) else {
        return;
    };
    let out = Command::new("python3")
        .args(["-c", SDK_SCRIPT])
        .env("PYTHONPATH", &sdk)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "the SDK script failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 4, "{stdout}");
    let (cmd, mut state) = messages();
    assert_eq!(
        lines[1].parse::<u32>().unwrap(),
        cmd.crc,
        "LowCmd_ checksum"
    );
    assert_eq!(
        lines[3].parse::<u32>().unwrap(),
        state.crc,
        "LowState_ checksum"
    );
    assert_eq!(hex(&cmd.to_cdr()), lines[0], "LowCmd_ CDR");
    assert_eq!(hex(&state.to_cdr_signed()), lines[2], "LowState_ CDR");
    let from_sdk = LowCmd::from_cdr(&unhex(lines[0])).unwrap();
    assert_eq!(from_sdk, cmd);
    assert!(from_sdk.crc_ok());
    assert_eq!(LowState::from_cdr(&unhex(lines[2])).unwrap(), state);
}
