//! `unitree_hg` messages of the G1 (unitree_sdk2 `include/unitree/idl/hg/`,
//! unitree_sdk2_python `unitree_sdk2py/idl/unitree_hg/msg/dds_/`): the command the
//! deployment code publishes on `rt/lowcmd` and the state the robot publishes on
//! `rt/lowstate`. Final, keyless types; 35 motor slots, of which the 29-DoF G1 uses the
//! first 29 in its joint order.

use super::cdr::{self, Layout, Message, Visit};
use super::crc::crc_of_c_struct;
use super::DecodeError;

/// Motor slots in every message (the G1 uses 29).
pub const MOTOR_SLOTS: usize = 35;
/// Size of `LowCmd_` as a C struct, bytes: what the checksum covers.
pub const LOW_CMD_C_BYTES: usize = 1004;
/// Size of `LowState_` as a C struct, bytes.
pub const LOW_STATE_C_BYTES: usize = 2092;
/// `mode_machine` of the 29-DoF G1.
pub const MODE_MACHINE_G1_29DOF: u8 = 5;

/// One motor's command: the robot applies `τ = tau + kp (q − q_meas) + kd (dq − dq_meas)`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MotorCmd {
    /// 1: enabled, 0: off.
    pub mode: u8,
    /// Target position, rad.
    pub q: f32,
    /// Target velocity, rad/s.
    pub dq: f32,
    /// Feed-forward torque, N m.
    pub tau: f32,
    /// Position gain, N m/rad.
    pub kp: f32,
    /// Velocity gain, N m s/rad.
    pub kd: f32,
    /// Unused.
    pub reserve: u32,
}

/// `unitree_hg::msg::dds_::LowCmd_`.
#[derive(Debug, Clone, PartialEq)]
pub struct LowCmd {
    /// Ankle/waist parallel-mechanism mode: 0 PR (pitch/roll), 1 AB.
    pub mode_pr: u8,
    /// The robot type the command is for (echo of `LowState::mode_machine`).
    pub mode_machine: u8,
    /// Per motor slot.
    pub motor_cmd: [MotorCmd; MOTOR_SLOTS],
    /// Unused.
    pub reserve: [u32; 4],
    /// Checksum of the rest ([`LowCmd::crc_of`]).
    pub crc: u32,
}

/// The IMU in the pelvis.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ImuState {
    /// Orientation, (w, x, y, z).
    pub quaternion: [f32; 4],
    /// Angular velocity in the IMU frame, rad/s.
    pub gyroscope: [f32; 3],
    /// Specific force in the IMU frame, m/s².
    pub accelerometer: [f32; 3],
    /// Roll, pitch, yaw, rad.
    pub rpy: [f32; 3],
    /// °C.
    pub temperature: i16,
}

/// One motor's state.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MotorState {
    /// Mode the motor is in.
    pub mode: u8,
    /// Position, rad.
    pub q: f32,
    /// Velocity, rad/s.
    pub dq: f32,
    /// Acceleration, rad/s².
    pub ddq: f32,
    /// Estimated torque, N m.
    pub tau_est: f32,
    /// Winding and case temperature, °C.
    pub temperature: [i16; 2],
    /// Supply voltage, V.
    pub vol: f32,
    /// Sensor words.
    pub sensor: [u32; 2],
    /// Fault bits.
    pub motorstate: u32,
    /// Unused.
    pub reserve: [u32; 4],
}

/// `unitree_hg::msg::dds_::LowState_`.
#[derive(Debug, Clone, PartialEq)]
pub struct LowState {
    /// Firmware version.
    pub version: [u32; 2],
    /// See [`LowCmd::mode_pr`].
    pub mode_pr: u8,
    /// The robot type ([`MODE_MACHINE_G1_29DOF`]).
    pub mode_machine: u8,
    /// Millisecond counter; deployment scripts wait for it to be non-zero.
    pub tick: u32,
    /// The pelvis IMU.
    pub imu_state: ImuState,
    /// Per motor slot.
    pub motor_state: [MotorState; MOTOR_SLOTS],
    /// The wireless remote's raw bytes (buttons at bytes 2–3, sticks as floats after).
    pub wireless_remote: [u8; 40],
    /// Unused.
    pub reserve: [u32; 4],
    /// Checksum of the rest ([`LowState::crc_of`]).
    pub crc: u32,
}

impl Default for LowCmd {
    fn default() -> Self {
        Self {
            mode_pr: 0,
            mode_machine: 0,
            motor_cmd: [MotorCmd::default(); MOTOR_SLOTS],
            reserve: [0; 4],
            crc: 0,
        }
    }
}

impl Default for LowState {
    fn default() -> Self {
        Self {
            version: [0; 2],
            mode_pr: 0,
            mode_machine: 0,
            tick: 0,
            imu_state: ImuState::default(),
            motor_state: [MotorState::default(); MOTOR_SLOTS],
            wireless_remote: [0; 40],
            reserve: [0; 4],
            crc: 0,
        }
    }
}

fn f32s(v: &mut impl Visit, xs: &mut [f32]) {
    xs.iter_mut().for_each(|x| v.f32(x));
}

fn u32s(v: &mut impl Visit, xs: &mut [u32]) {
    xs.iter_mut().for_each(|x| v.u32(x));
}

impl MotorCmd {
    fn walk(&mut self, v: &mut impl Visit) {
        v.begin_struct();
        v.u8(&mut self.mode);
        for x in [
            &mut self.q,
            &mut self.dq,
            &mut self.tau,
            &mut self.kp,
            &mut self.kd,
        ] {
            v.f32(x);
        }
        v.u32(&mut self.reserve);
        v.end_struct();
    }
}

impl Message for LowCmd {
    const TYPE_NAME: &'static str = "unitree_hg::msg::dds_::LowCmd_";
    fn walk(&mut self, v: &mut impl Visit) {
        v.begin_struct();
        v.u8(&mut self.mode_pr);
        v.u8(&mut self.mode_machine);
        self.motor_cmd.iter_mut().for_each(|m| m.walk(v));
        u32s(v, &mut self.reserve);
        v.u32(&mut self.crc);
        v.end_struct();
    }
}

impl Message for ImuState {
    /// Also a topic of its own: the G1's torso IMU on `rt/secondary_imu`.
    const TYPE_NAME: &'static str = "unitree_hg::msg::dds_::IMUState_";
    fn walk(&mut self, v: &mut impl Visit) {
        v.begin_struct();
        f32s(v, &mut self.quaternion);
        f32s(v, &mut self.gyroscope);
        f32s(v, &mut self.accelerometer);
        f32s(v, &mut self.rpy);
        v.i16(&mut self.temperature);
        v.end_struct();
    }
}

impl MotorState {
    fn walk(&mut self, v: &mut impl Visit) {
        v.begin_struct();
        v.u8(&mut self.mode);
        for x in [&mut self.q, &mut self.dq, &mut self.ddq, &mut self.tau_est] {
            v.f32(x);
        }
        self.temperature.iter_mut().for_each(|t| v.i16(t));
        v.f32(&mut self.vol);
        u32s(v, &mut self.sensor);
        v.u32(&mut self.motorstate);
        u32s(v, &mut self.reserve);
        v.end_struct();
    }
}

impl Message for LowState {
    const TYPE_NAME: &'static str = "unitree_hg::msg::dds_::LowState_";
    fn walk(&mut self, v: &mut impl Visit) {
        v.begin_struct();
        u32s(v, &mut self.version);
        v.u8(&mut self.mode_pr);
        v.u8(&mut self.mode_machine);
        v.u32(&mut self.tick);
        self.imu_state.walk(v);
        self.motor_state.iter_mut().for_each(|m| m.walk(v));
        self.wireless_remote.iter_mut().for_each(|b| v.u8(b));
        u32s(v, &mut self.reserve);
        v.u32(&mut self.crc);
        v.end_struct();
    }
}

impl LowCmd {
    /// The checksum the robot expects in `crc`: over the C struct, `crc` left out.
    pub fn crc_of(&self) -> u32 {
        crc_of_c_struct(&cdr::encode(self, Layout::C))
    }

    /// Whether `crc` is right: the robot ignores a command whose checksum is wrong.
    pub fn crc_ok(&self) -> bool {
        self.crc == self.crc_of()
    }

    /// A command from its CDR payload (XCDR1 or XCDR2, either byte order).
    pub fn from_cdr(payload: &[u8]) -> Result<Self, DecodeError> {
        cdr::decode_cdr(payload)
    }

    /// The CDR payload (XCDR1, little-endian), as written.
    pub fn to_cdr(&self) -> Vec<u8> {
        cdr::encode(self, Layout::Cdr)
    }
}

impl LowState {
    /// The checksum over the C struct, `crc` left out.
    pub fn crc_of(&self) -> u32 {
        crc_of_c_struct(&cdr::encode(self, Layout::C))
    }

    /// Sets `crc`; then the CDR payload (XCDR1, little-endian).
    pub fn to_cdr_signed(&mut self) -> Vec<u8> {
        self.crc = self.crc_of();
        cdr::encode(self, Layout::Cdr)
    }

    /// A state from its CDR payload.
    pub fn from_cdr(payload: &[u8]) -> Result<Self, DecodeError> {
        cdr::decode_cdr(payload)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_c_structs_have_the_sdks_sizes() {
        assert_eq!(
            cdr::encode(&LowCmd::default(), Layout::C).len(),
            LOW_CMD_C_BYTES
        );
        assert_eq!(
            cdr::encode(&LowState::default(), Layout::C).len(),
            LOW_STATE_C_BYTES
        );
    }

    /// The values unitree_sdk2py's `CRC().Crc` gives all-zero messages.
    #[test]
    fn all_zero_messages_have_the_sdks_checksums() {
        assert_eq!(LowCmd::default().crc_of(), 4_262_932_383);
        assert_eq!(LowState::default().crc_of(), 3_595_284_554);
    }

    #[test]
    fn the_checksum_ignores_the_crc_field_and_sees_every_other_field() {
        let mut cmd = LowCmd {
            crc: 12345,
            ..Default::default()
        };
        assert_eq!(cmd.crc_of(), 4_262_932_383);
        cmd.motor_cmd[34].kd = 1.0; // the last motor's last float
        assert_ne!(cmd.crc_of(), 4_262_932_383);
        let mut state = LowState::default();
        state.reserve[3] = 1;
        assert_ne!(state.crc_of(), 3_595_284_554);
    }

    fn sample_cmd() -> LowCmd {
        let mut cmd = LowCmd {
            mode_pr: 0,
            mode_machine: MODE_MACHINE_G1_29DOF,
            ..Default::default()
        };
        for (i, m) in cmd.motor_cmd.iter_mut().enumerate().take(29) {
            *m = MotorCmd {
                mode: 1,
                q: 0.01 * i as f32,
                dq: -0.5,
                tau: 0.25,
                kp: 100.0 + i as f32,
                kd: 2.5,
                reserve: i as u32,
            };
        }
        cmd.crc = cmd.crc_of();
        cmd
    }

    #[test]
    fn a_command_survives_cdr_and_keeps_its_checksum() {
        let cmd = sample_cmd();
        let wire = cmd.to_cdr();
        assert_eq!(&wire[..4], &[0, 1, 0, 0], "XCDR1 little-endian, no padding");
        // mode_pr, mode_machine, 35 motors of 28 bytes (u8, 3 padding, 6 × 4), the
        // first one's mode packed right after mode_machine, reserve[4], crc: 1000 bytes
        // of data, 4 fewer than the C struct (which pads the first motor to 4).
        assert_eq!(wire.len(), 4 + 1000);
        let back = LowCmd::from_cdr(&wire).unwrap();
        assert_eq!(back, cmd);
        assert!(back.crc_ok());
        let mut corrupted = wire.clone();
        corrupted[40] ^= 0x01;
        assert!(!LowCmd::from_cdr(&corrupted).unwrap().crc_ok());
    }

    #[test]
    fn a_state_survives_cdr_in_both_encodings_and_byte_orders() {
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
        let wire = state.to_cdr_signed();
        assert_eq!(LowState::from_cdr(&wire).unwrap(), state);
        // XCDR2 (plain, final type) lays these fields out alike.
        let mut xcdr2 = wire.clone();
        xcdr2[1] = 0x07;
        assert_eq!(LowState::from_cdr(&xcdr2).unwrap(), state);
        // Big-endian: every field byte-swapped in place (all at their natural alignment).
        let mut w = cdr::Writer::new(Layout::Cdr);
        state.clone().walk(&mut SwapWriter(&mut w));
        let mut be = w.finish();
        be[1] = 0x00;
        assert_eq!(LowState::from_cdr(&be).unwrap(), state);
    }

    /// Writes every field big-endian (to test the reader's byte order).
    struct SwapWriter<'a>(&'a mut cdr::Writer);
    impl Visit for SwapWriter<'_> {
        fn begin_struct(&mut self) {}
        fn end_struct(&mut self) {}
        fn u8(&mut self, v: &mut u8) {
            self.0.u8(v);
        }
        fn i16(&mut self, v: &mut i16) {
            let mut s = i16::from_le_bytes(v.to_be_bytes());
            self.0.i16(&mut s);
        }
        fn u32(&mut self, v: &mut u32) {
            let mut s = u32::from_le_bytes(v.to_be_bytes());
            self.0.u32(&mut s);
        }
        fn f32(&mut self, v: &mut f32) {
            let mut s = f32::from_le_bytes(v.to_be_bytes());
            self.0.f32(&mut s);
        }
    }

    #[test]
    fn a_short_or_foreign_payload_is_an_error() {
        let wire = sample_cmd().to_cdr();
        assert!(matches!(
            LowCmd::from_cdr(&wire[..500]),
            Err(DecodeError::Truncated { .. })
        ));
        let mut pl = wire.clone();
        pl[1] = 0x03; // PL_CDR_LE: a parameter list, not a final type
        assert!(matches!(
            LowCmd::from_cdr(&pl),
            Err(DecodeError::Encapsulation { kind: 3, .. })
        ));
        assert!(LowCmd::from_cdr(&[0, 1]).is_err());
    }
}
