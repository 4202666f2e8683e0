//! The robot's DDS endpoints (`thorarena::dds::RobotEndpoints`, on rustdds) talk to
//! Unitree's own Python SDK (unitree_sdk2_python on PyPI's `cyclonedds` 11.0.1) over
//! loopback on domain 0: the SDK's subscriber receives `rt/lowstate` with a checksum it
//! accepts and `rt/wirelesscontroller` (`unitree_go`) with the buttons held, and its
//! `rt/lowcmd` messages arrive here decoded, checksums intact — but for the one the script
//! corrupts, which fails the check. Both ends run in a private network namespace when root
//! allows it (`netns`). Skipped, saying so, when `../shared/reference` (the SDK) or
//! Python's `cyclonedds` is absent; never in CI.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use thorarena::dds::unitree_hg::MODE_MACHINE_G1_29DOF;
use thorarena::dds::{ImuState, LowState, RobotEndpoints, WirelessController};
mod netns;
mod prereq;

/// Unitree's SDK as a deployment script uses it: waits for states (and the remote's
/// message), checks one's CRC, then sends 50 commands at 100 Hz (the 11th with a flipped checksum bit).
const SDK_SCRIPT: &str = r#"
import sys, time
from unitree_sdk2py.core.channel import ChannelFactoryInitialize, ChannelPublisher, ChannelSubscriber
from unitree_sdk2py.idl.default import unitree_hg_msg_dds__LowCmd_
from unitree_sdk2py.idl.unitree_hg.msg.dds_ import LowCmd_, LowState_
from unitree_sdk2py.idl.unitree_go.msg.dds_ import WirelessController_
from unitree_sdk2py.utils.crc import CRC

ChannelFactoryInitialize(0, "lo")
states = []
sub = ChannelSubscriber("rt/lowstate", LowState_)
sub.Init(lambda m: states.append(m), 10)
remotes = []
remote_sub = ChannelSubscriber("rt/wirelesscontroller", WirelessController_)
remote_sub.Init(lambda m: remotes.append(m), 10)
pub = ChannelPublisher("rt/lowcmd", LowCmd_)
pub.Init()
deadline = time.time() + 30
while (len(states) < 5 or not remotes) and time.time() < deadline:
    time.sleep(0.01)
if not states or not remotes:
    print("no state or no remote within 30 s", flush=True)
    sys.exit(1)
s = states[-1]
print("state", s.tick, int(CRC().Crc(s) == s.crc), s.motor_state[3].q, flush=True)
print("remote", remotes[-1].keys, remotes[-1].lx, flush=True)
crc = CRC()
for k in range(50):
    c = unitree_hg_msg_dds__LowCmd_()
    c.mode_machine = 5
    for i in range(29):
        m = c.motor_cmd[i]
        m.mode, m.q, m.kp, m.kd = 1, i / 8, 60.0, 1.5
    c.reserve[0] = k
    c.crc = crc.Crc(c)
    if k == 10:
        c.crc ^= 1
    pub.Write(c)
    time.sleep(0.01)
time.sleep(0.2)
print("sent", flush=True)
"#;

#[test]
fn the_robot_endpoints_exchange_checked_messages_with_unitrees_python_sdk() {
    const TEST: &str = "dds_transport::python_sdk";
    let Some(sdk) = prereq::unitree_sdk(TEST) else {
        return;
    };
    // This thread, rustdds' threads and the Python peer, in a network of their own.
    netns::enter_private_network(TEST);
    let loopback = std::net::IpAddr::from([127, 0, 0, 1]);
    let mut robot = RobotEndpoints::join(0, Some(loopback)).expect("join domain 0 on lo");
    let mut sdk_side = Command::new("python3")
        .args(["-c", SDK_SCRIPT])
        .env("PYTHONPATH", &sdk)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut state = LowState {
        mode_machine: MODE_MACHINE_G1_29DOF,
        ..Default::default()
    };
    state.motor_state[3].q = 0.75;
    state.imu_state.quaternion = [1.0, 0.0, 0.0, 0.0];
    let torso = ImuState {
        quaternion: [1.0, 0.0, 0.0, 0.0],
        ..Default::default()
    };
    // select + A, and a stick off centre.
    let remote = WirelessController {
        keys: 264,
        lx: 0.25,
        ..Default::default()
    };
    let mut commands = Vec::new();
    let start = Instant::now();
    // The robot's loop: a state every 2 ms (500 Hz), commands collected, until the
    // script is done (or 60 s, then it is stopped by its pid).
    let status = loop {
        state.tick += 1;
        state.crc = state.crc_of();
        robot.publish(&state, &torso, &remote).expect("publish");
        commands.extend(robot.commands().expect("read commands"));
        if let Some(status) = sdk_side.try_wait().unwrap() {
            break Some(status);
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = sdk_side.kill();
            break None;
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    commands.extend(robot.commands().expect("read commands"));
    let out = sdk_side.wait_with_output().unwrap();
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(status.is_some_and(|s| s.success()), "SDK script: {said}");
    let line = said.lines().find(|l| l.starts_with("state ")).unwrap();
    let fields: Vec<&str> = line.split(' ').collect();
    assert!(fields[1].parse::<u32>().unwrap() > 0, "{line}");
    assert_eq!(
        fields[2], "1",
        "the SDK rejected the state's checksum: {line}"
    );
    assert_eq!(fields[3], "0.75", "{line}");
    let remote_line = said.lines().find(|l| l.starts_with("remote ")).unwrap();
    assert_eq!(remote_line, "remote 264 0.25", "{said}");

    assert!(
        commands.len() >= 40,
        "{} of 50 commands arrived: {said}",
        commands.len()
    );
    for (c, _writer) in &commands {
        assert_eq!(c.mode_machine, MODE_MACHINE_G1_29DOF);
        assert_eq!(c.motor_cmd[8].q, 1.0);
        assert_eq!((c.motor_cmd[8].kp, c.motor_cmd[8].kd), (60.0, 1.5));
        assert_eq!(c.crc_ok(), c.reserve[0] != 10, "command {}", c.reserve[0]);
    }
    assert_eq!(robot.undecodable_commands(), 0);
}
