//! The robot's end of Unitree's DDS interface on `rustdds`: `rt/lowstate`,
//! `rt/secondary_imu` and `rt/wirelesscontroller` written, `rt/lowcmd` read, each message
//! through this module's own codec ([`UnitreeCdr`], plugged into rustdds as its
//! serializer adapter).
//!
//! QoS: the writers offer reliable delivery and the reader asks for best effort, so they
//! match whatever the deployment code's CycloneDDS asks or offers (a reader may not ask for
//! more than a writer offers). The writers keep the last message (a robot's state is only
//! ever wanted fresh); the command reader keeps every command until it is taken, so each
//! is counted and timed, though only the newest is applied.

use super::cdr::{self, Layout, Message};
use super::{DecodeError, ImuState, LowCmd, LowState, WirelessController};
use rustdds::no_key::{DataReader, DataWriter, Decode, DefaultDecoder};
use rustdds::no_key::{DeserializerAdapter, SerializerAdapter};
use rustdds::policy::{History, Reliability};
use rustdds::{
    DomainParticipant, DomainParticipantBuilder, QosPolicies, QosPolicyBuilder,
    RepresentationIdentifier, TopicKind,
};
use std::marker::PhantomData;

/// The robot's state, at the robot's rate.
pub const LOW_STATE_TOPIC: &str = "rt/lowstate";
/// The torso IMU's state.
pub const SECONDARY_IMU_TOPIC: &str = "rt/secondary_imu";
/// The wireless remote (also in `rt/lowstate`'s `wireless_remote`).
pub const WIRELESS_CONTROLLER_TOPIC: &str = "rt/wirelesscontroller";
/// Motor commands from the deployment code.
pub const LOW_COMMAND_TOPIC: &str = "rt/lowcmd";

/// The largest DDS domain id whose RTPS ports fit in 16 bits.
pub const MAX_DOMAIN: u16 = 232;

/// Why no command started the episode, from what arrived: nothing at all (the deployment
/// code elsewhere), or commands the robot would ignore too.
fn no_command_why(c: &super::bridge::CommandCounts) -> String {
    if c.received == 0 && c.undecodable == 0 {
        return "none arrived at all: is the deployment code running on the same DDS domain and network interface?".into();
    }
    format!(
        "{} arrived and none was usable — {} with a bad checksum (the robot ignores those: is the CRC computed over the C struct?), {} undecodable, {} with non-finite or negative values or a motor mode other than 0 or 1",
        c.received + c.undecodable,
        c.bad_crc,
        c.undecodable,
        c.unusable
    )
}

/// Why the DDS interface failed.
#[derive(Debug, thiserror::Error)]
pub enum DdsError {
    /// A participant, topic, reader or writer could not be created.
    #[error("DDS: creating the {what}: {detail}")]
    Create {
        /// What was being created.
        what: &'static str,
        /// rustdds' account.
        detail: String,
    },
    /// A message could not be written.
    #[error("DDS: writing {topic}: {detail}")]
    Write {
        /// The topic.
        topic: &'static str,
        /// rustdds' account.
        detail: String,
    },
    /// No usable command arrived in time to start the episode: why, by what did arrive.
    #[error("no valid command on {LOW_COMMAND_TOPIC} within {waited:?}: {}", no_command_why(.counts))]
    NoCommand {
        /// How long the bridge waited.
        waited: std::time::Duration,
        /// What arrived meanwhile.
        counts: super::bridge::CommandCounts,
    },
    /// A DDS domain RTPS cannot map to ports.
    #[error("DDS domain {0}: give 0 to {MAX_DOMAIN} (RTPS puts domain d's ports at 7400 + 250·d, which must fit in 16 bits)")]
    Domain(u16),
    /// The command reader failed (not a bad message: those are counted).
    #[error("DDS: reading {LOW_COMMAND_TOPIC}: {0}")]
    Read(String),
    /// The simulator clock for holosoma could not be served.
    #[error(transparent)]
    Clock(#[from] super::zmq_clock::ZmqClockError),
}

/// rustdds' serializer and deserializer adapter for the `unitree_hg` messages: XCDR1
/// little-endian out; XCDR1 and plain XCDR2, either byte order, in.
pub struct UnitreeCdr<M>(PhantomData<M>);

impl<M: Message + Clone> SerializerAdapter<M> for UnitreeCdr<M> {
    type Error = std::convert::Infallible;

    fn output_encoding() -> RepresentationIdentifier {
        RepresentationIdentifier::CDR_LE
    }

    fn to_bytes(value: &M) -> Result<rustdds::bytes::Bytes, Self::Error> {
        // rustdds writes the encapsulation header itself.
        let mut bytes = cdr::encode(value, Layout::Cdr);
        bytes.drain(..4);
        Ok(bytes.into())
    }
}

const READ_ENCODINGS: [RepresentationIdentifier; 4] = [
    RepresentationIdentifier::CDR_LE,
    RepresentationIdentifier::CDR_BE,
    RepresentationIdentifier::XCDR2_LE,
    RepresentationIdentifier::XCDR2_BE,
];

impl<M: Message> DeserializerAdapter<M> for UnitreeCdr<M> {
    type Error = DecodeError;
    type Decoded = M;

    fn supported_encodings() -> &'static [RepresentationIdentifier] {
        &READ_ENCODINGS
    }

    fn transform_decoded(decoded: M) -> M {
        decoded
    }
}

/// The decoder rustdds calls with the data after the encapsulation header.
pub struct UnitreeDecoder<M>(PhantomData<M>);

impl<M> Clone for UnitreeDecoder<M> {
    fn clone(&self) -> Self {
        Self(PhantomData)
    }
}

impl<'de, M: Message> Decode<'de, M> for UnitreeDecoder<M> {
    type Error = DecodeError;

    fn decode_bytes(
        self,
        input_bytes: &'de [u8],
        encoding: RepresentationIdentifier,
    ) -> Result<M, DecodeError> {
        cdr::decode_cdr_body(input_bytes, u16::from_be_bytes(encoding.to_bytes()))
    }
}

impl<M: Message> DefaultDecoder<M> for UnitreeCdr<M> {
    type Decoder = UnitreeDecoder<M>;
    const DECODER: Self::Decoder = UnitreeDecoder(PhantomData);
}

/// The robot's side of the interface on one DDS domain.
pub struct RobotEndpoints {
    low_state: DataWriter<LowState, UnitreeCdr<LowState>>,
    secondary_imu: DataWriter<ImuState, UnitreeCdr<ImuState>>,
    wireless_controller: DataWriter<WirelessController, UnitreeCdr<WirelessController>>,
    low_command: DataReader<LowCmd, UnitreeCdr<LowCmd>>,
    /// `rt/lowstate` as a deployment reads it: a writer there other than ours is another
    /// robot (a second bridge) on the domain, whose states the deployment may be reading.
    state_watch: DataReader<LowState, UnitreeCdr<LowState>>,
    motion_switcher: super::motion_switcher::MotionSwitcher,
    /// Commands that arrived and could not be decoded.
    undecodable: u64,
    // Last: the readers and writers go before their participant.
    _participant: DomainParticipant,
}

impl RobotEndpoints {
    /// Joins DDS domain `domain` (Unitree's scripts use 0) as the robot; with
    /// `only_address` (e.g. 127.0.0.1, what `lo` carries) discovery and multicast use that
    /// interface alone, so nothing leaves the machine.
    pub fn join(domain: u16, only_address: Option<std::net::IpAddr>) -> Result<Self, DdsError> {
        if domain > MAX_DOMAIN {
            return Err(DdsError::Domain(domain));
        }
        let create = |what: &'static str| {
            move |e: rustdds::dds::CreateError| DdsError::Create {
                what,
                detail: e.to_string(),
            }
        };
        let mut builder = DomainParticipantBuilder::new(domain);
        if let Some(address) = only_address {
            builder = builder.with_only_networks([address]);
        }
        let participant = builder.build().map_err(create("domain participant"))?;
        let writer_qos = QosPolicyBuilder::new()
            .reliability(Reliability::Reliable {
                max_blocking_time: rustdds::Duration::ZERO,
            })
            .history(History::KeepLast { depth: 1 })
            .build();
        // Every command is kept until taken (to count them and time their arrivals);
        // the robot applies the newest.
        let reader_qos = QosPolicyBuilder::new()
            .reliability(Reliability::BestEffort)
            .history(History::KeepLast { depth: 256 })
            .build();
        let topic = |name: &str, type_name: &str, qos: &QosPolicies| {
            participant
                .create_topic(name.into(), type_name.into(), qos, TopicKind::NoKey)
                .map_err(create("topic"))
        };
        let publisher = participant
            .create_publisher(&writer_qos)
            .map_err(create("publisher"))?;
        let subscriber = participant
            .create_subscriber(&reader_qos)
            .map_err(create("subscriber"))?;
        let low_state_topic = topic(LOW_STATE_TOPIC, LowState::TYPE_NAME, &writer_qos)?;
        let low_state = publisher
            .create_datawriter_no_key::<LowState, UnitreeCdr<LowState>>(&low_state_topic, None)
            .map_err(create("rt/lowstate writer"))?;
        let watch_qos = QosPolicyBuilder::new()
            .reliability(Reliability::BestEffort)
            .history(History::KeepLast { depth: 1 })
            .build();
        let state_watch = subscriber
            .create_datareader_no_key::<LowState, UnitreeCdr<LowState>>(
                &low_state_topic,
                Some(watch_qos),
            )
            .map_err(create("rt/lowstate watcher"))?;
        let secondary_imu = publisher
            .create_datawriter_no_key::<ImuState, UnitreeCdr<ImuState>>(
                &topic(SECONDARY_IMU_TOPIC, ImuState::TYPE_NAME, &writer_qos)?,
                None,
            )
            .map_err(create("rt/secondary_imu writer"))?;
        let wireless_controller = publisher
            .create_datawriter_no_key::<WirelessController, UnitreeCdr<WirelessController>>(
                &topic(
                    WIRELESS_CONTROLLER_TOPIC,
                    WirelessController::TYPE_NAME,
                    &writer_qos,
                )?,
                None,
            )
            .map_err(create("rt/wirelesscontroller writer"))?;
        let low_command = subscriber
            .create_datareader_no_key::<LowCmd, UnitreeCdr<LowCmd>>(
                &topic(LOW_COMMAND_TOPIC, LowCmd::TYPE_NAME, &reader_qos)?,
                None,
            )
            .map_err(create("rt/lowcmd reader"))?;
        let motion_switcher = super::motion_switcher::MotionSwitcher::new(
            &participant,
            &publisher,
            &subscriber,
            &writer_qos,
            &reader_qos,
        )?;
        Ok(Self {
            low_state,
            secondary_imu,
            wireless_controller,
            low_command,
            state_watch,
            motion_switcher,
            undecodable: 0,
            _participant: participant,
        })
    }

    /// Publishes the robot's state (its checksum as given), the torso IMU's and the
    /// wireless remote's.
    pub fn publish(
        &self,
        state: &LowState,
        torso_imu: &ImuState,
        remote: &WirelessController,
    ) -> Result<(), DdsError> {
        self.low_state
            .write(state.clone(), None)
            .map_err(|e| DdsError::Write {
                topic: LOW_STATE_TOPIC,
                detail: e.to_string(),
            })?;
        self.secondary_imu
            .write(*torso_imu, None)
            .map_err(|e| DdsError::Write {
                topic: SECONDARY_IMU_TOPIC,
                detail: e.to_string(),
            })?;
        self.wireless_controller
            .write(*remote, None)
            .map_err(|e| DdsError::Write {
                topic: WIRELESS_CONTROLLER_TOPIC,
                detail: e.to_string(),
            })
    }

    /// Every command that arrived since the last call, oldest first (checksums not yet
    /// checked: that is the robot's business, [`LowCmd::crc_ok`]).
    pub fn commands(&mut self) -> Result<Vec<(LowCmd, rustdds::GUID)>, DdsError> {
        let mut out = Vec::new();
        loop {
            match self.low_command.take_next_sample() {
                Ok(Some(sample)) => {
                    let writer = sample.sample_info().writer_guid();
                    out.push((sample.into_value(), writer));
                }
                Ok(None) => return Ok(out),
                Err(rustdds::dds::ReadError::Deserialization { .. }) => self.undecodable += 1,
                Err(e) => return Err(DdsError::Read(e.to_string())),
            }
        }
    }

    /// The writers of `rt/lowstate` other than this robot's whose states arrived since
    /// the last call: other robots (bridges) on the domain.
    pub fn other_robots(&mut self) -> Vec<String> {
        use rustdds::RTPSEntity;
        let own = self.low_state.guid();
        let mut others = Vec::new();
        while let Ok(Some(sample)) = self.state_watch.take_next_sample() {
            let writer = sample.sample_info().writer_guid();
            if writer.prefix != own.prefix {
                others.push(guid_text(&writer));
            }
        }
        others
    }

    /// Answers the robot's services' requests (`motion_switcher`) that arrived.
    pub fn serve_services(&mut self) -> Result<(), DdsError> {
        self.motion_switcher.serve()
    }

    /// Service requests answered so far, by API id.
    pub fn service_calls(&self) -> &[i64] {
        &self.motion_switcher.answered
    }

    /// Commands that arrived and could not be decoded, so far.
    pub fn undecodable_commands(&self) -> u64 {
        self.undecodable
    }
}

/// A DDS writer's GUID as people read it: its 12-byte participant prefix and 4-byte
/// entity id in hex (`0a1b…:00000102`), not Rust's debug text of the struct.
pub fn guid_text(guid: &rustdds::GUID) -> String {
    let bytes = guid.to_bytes();
    let hex = |b: &[u8]| b.iter().map(|x| format!("{x:02x}")).collect::<String>();
    format!("{}:{}", hex(&bytes[..12]), hex(&bytes[12..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_adapter_writes_the_codecs_bytes_without_the_header_and_reads_them_back() {
        let mut cmd = LowCmd {
            mode_machine: 5,
            ..Default::default()
        };
        cmd.motor_cmd[4].q = 0.5;
        cmd.crc = cmd.crc_of();
        let body = <UnitreeCdr<LowCmd> as SerializerAdapter<LowCmd>>::to_bytes(&cmd).unwrap();
        assert_eq!(&body[..], &cmd.to_cdr()[4..]);
        let back = UnitreeCdr::<LowCmd>::DECODER
            .decode_bytes(&body, RepresentationIdentifier::CDR_LE)
            .unwrap();
        assert_eq!(back, cmd);
        assert!(UnitreeCdr::<LowCmd>::DECODER
            .decode_bytes(&body, RepresentationIdentifier::PL_CDR_LE)
            .is_err());
        assert!(UnitreeCdr::<LowCmd>::DECODER
            .decode_bytes(&body[..100], RepresentationIdentifier::CDR_LE)
            .is_err());
    }
}
