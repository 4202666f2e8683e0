//! The robot's `motion_switcher` service, as much of it as low-level deployment code asks
//! before it takes the motors: Unitree's RPC over DDS (`rt/api/motion_switcher/request`
//! in, `rt/api/motion_switcher/response` out, `unitree_api::msg::dds_::Request_` and
//! `Response_`, matched by request id). A script first asks which motion mode runs
//! (CheckMode, API 1001) and releases it (ReleaseMode, 1003) until none does; the
//! simulated robot never runs one, so it says so and accepts every release.
//!
//! These messages hold strings and byte sequences, so they go through rustdds' serde CDR
//! adapter rather than our fixed-size codec.

use super::transport::DdsError;
use rustdds::no_key::{DataReader, DataWriter};
use rustdds::{CDRDeserializerAdapter, CDRSerializerAdapter, Publisher, QosPolicies, Subscriber};
use rustdds::{DomainParticipant, TopicKind};
use serde::{Deserialize, Serialize};

/// Requests to the service.
pub const REQUEST_TOPIC: &str = "rt/api/motion_switcher/request";
/// Its answers.
pub const RESPONSE_TOPIC: &str = "rt/api/motion_switcher/response";
/// CheckMode: which motion mode runs (`{"form":…,"name":…}`; empty name: none).
pub const API_CHECK_MODE: i64 = 1001;
/// SelectMode.
pub const API_SELECT_MODE: i64 = 1002;
/// ReleaseMode.
pub const API_RELEASE_MODE: i64 = 1003;
/// The service's API version query (internal API 1).
pub const API_VERSION: i64 = 1;
/// Unitree's RPC status for an API the server does not implement.
pub const STATUS_NOT_IMPLEMENTED: i32 = 3203;

/// `unitree_api::msg::dds_::RequestIdentity_`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RequestIdentity {
    /// The caller's request id (answers carry it back).
    pub id: i64,
    /// Which API is called.
    pub api_id: i64,
}

/// `unitree_api::msg::dds_::RequestLease_`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RequestLease {
    /// Lease id (0: none).
    pub id: i64,
}

/// `unitree_api::msg::dds_::RequestPolicy_`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RequestPolicy {
    /// Priority.
    pub priority: i32,
    /// The caller wants no answer.
    pub noreply: bool,
}

/// `unitree_api::msg::dds_::RequestHeader_`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RequestHeader {
    /// Who asks what.
    pub identity: RequestIdentity,
    /// Lease.
    pub lease: RequestLease,
    /// Policy.
    pub policy: RequestPolicy,
}

/// `unitree_api::msg::dds_::Request_`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Request {
    /// Header.
    pub header: RequestHeader,
    /// JSON parameters.
    pub parameter: String,
    /// Binary parameters.
    pub binary: Vec<u8>,
}

/// `unitree_api::msg::dds_::ResponseStatus_`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ResponseStatus {
    /// 0: success.
    pub code: i32,
}

/// `unitree_api::msg::dds_::ResponseHeader_`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ResponseHeader {
    /// The request answered.
    pub identity: RequestIdentity,
    /// Outcome.
    pub status: ResponseStatus,
}

/// `unitree_api::msg::dds_::Response_`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Response {
    /// Header.
    pub header: ResponseHeader,
    /// JSON result.
    pub data: String,
    /// Binary result.
    pub binary: Vec<u8>,
}

/// The answer of the simulated robot to `request`: no motion mode runs, releasing one
/// succeeds, the version is the SDK's; anything else is not implemented.
pub fn answer(request: &Request) -> Response {
    let api_id = request.header.identity.api_id;
    let (code, data) = match api_id {
        API_CHECK_MODE => (0, r#"{"form":"0","name":""}"#),
        API_RELEASE_MODE | API_SELECT_MODE => (0, ""),
        API_VERSION => (0, "1.0.0.1"),
        _ => (STATUS_NOT_IMPLEMENTED, ""),
    };
    Response {
        header: ResponseHeader {
            identity: request.header.identity.clone(),
            status: ResponseStatus { code },
        },
        data: data.into(),
        binary: Vec::new(),
    }
}

/// The service's reader and writer.
pub struct MotionSwitcher {
    requests: DataReader<Request, CDRDeserializerAdapter<Request>>,
    responses: DataWriter<Response, CDRSerializerAdapter<Response>>,
    /// Requests answered so far, by API id.
    pub answered: Vec<i64>,
}

impl MotionSwitcher {
    /// The service on `participant`.
    pub fn new(
        participant: &DomainParticipant,
        publisher: &Publisher,
        subscriber: &Subscriber,
        writer_qos: &QosPolicies,
        reader_qos: &QosPolicies,
    ) -> Result<Self, DdsError> {
        let create = |what: &'static str| {
            move |e: rustdds::dds::CreateError| DdsError::Create {
                what,
                detail: e.to_string(),
            }
        };
        let request_topic = participant
            .create_topic(
                REQUEST_TOPIC.into(),
                "unitree_api::msg::dds_::Request_".into(),
                reader_qos,
                TopicKind::NoKey,
            )
            .map_err(create("topic"))?;
        let response_topic = participant
            .create_topic(
                RESPONSE_TOPIC.into(),
                "unitree_api::msg::dds_::Response_".into(),
                writer_qos,
                TopicKind::NoKey,
            )
            .map_err(create("topic"))?;
        Ok(Self {
            requests: subscriber
                .create_datareader_no_key_cdr::<Request>(&request_topic, None)
                .map_err(create("motion_switcher request reader"))?,
            responses: publisher
                .create_datawriter_no_key_cdr::<Response>(&response_topic, None)
                .map_err(create("motion_switcher response writer"))?,
            answered: Vec::new(),
        })
    }

    /// Answers every request that arrived.
    pub fn serve(&mut self) -> Result<(), DdsError> {
        loop {
            let request = match self.requests.take_next_sample() {
                Ok(Some(sample)) => sample.into_value(),
                Ok(None) => return Ok(()),
                Err(rustdds::dds::ReadError::Deserialization { .. }) => continue,
                Err(e) => return Err(DdsError::Read(e.to_string())),
            };
            if request.header.policy.noreply {
                continue;
            }
            self.answered.push(request.header.identity.api_id);
            self.responses
                .write(answer(&request), None)
                .map_err(|e| DdsError::Write {
                    topic: RESPONSE_TOPIC,
                    detail: e.to_string(),
                })?;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_mode_says_no_mode_runs_and_unknown_apis_are_not_implemented() {
        let mut request = Request::default();
        request.header.identity = RequestIdentity {
            id: 77,
            api_id: API_CHECK_MODE,
        };
        let check = answer(&request);
        assert_eq!(check.header.identity.id, 77);
        assert_eq!(check.header.status.code, 0);
        let json: serde_json::Value = serde_json::from_str(&check.data).unwrap();
        assert_eq!(json["name"], "");
        request.header.identity.api_id = API_RELEASE_MODE;
        assert_eq!(answer(&request).header.status.code, 0);
        request.header.identity.api_id = 1999;
        assert_eq!(answer(&request).header.status.code, STATUS_NOT_IMPLEMENTED);
    }
}
