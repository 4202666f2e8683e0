//! Tests of the C ABI (`ffi.rs`), in their own file to keep the ABI readable.

use super::*;
use crate::handshake::Status;

#[test]
fn refusal_statuses_keep_their_wire_numbers() {
    for wire in 0..=7u32 {
        let status = Status::from_u32(wire).unwrap();
        assert_eq!(ThorarenaStatus::from_refusal(status) as u32, wire);
    }
}

#[test]
fn every_status_has_its_c_name() {
    for s in ThorarenaStatus::ALL {
        // SAFETY: the function returns a static NUL-terminated string.
        let name = unsafe { CStr::from_ptr(thorarena_status_name(s as c_int)) };
        assert_eq!(name, s.name());
        assert!(name.to_str().unwrap().starts_with("THORARENA_STATUS_"));
    }
    // SAFETY: as above.
    let unknown = unsafe { CStr::from_ptr(thorarena_status_name(999)) };
    assert_eq!(unknown, c"THORARENA_STATUS_UNKNOWN");
}

#[test]
fn null_arguments_are_invalid_not_a_crash() {
    let mut out = std::ptr::null_mut();
    // SAFETY: NULL is allowed for every pointer argument.
    unsafe {
        assert_eq!(
            thorarena_connect(std::ptr::null(), &mut out),
            ThorarenaStatus::InvalidArgument
        );
        assert!(out.is_null());
        assert_eq!(
            thorarena_send(std::ptr::null_mut()),
            ThorarenaStatus::InvalidArgument
        );
        let (mut o, mut a) = (std::ptr::null(), std::ptr::null_mut());
        assert_eq!(
            thorarena_next_step(std::ptr::null_mut(), 0, &mut o, &mut a),
            ThorarenaStatus::InvalidArgument
        );
        thorarena_close(std::ptr::null_mut());
        let message = CStr::from_ptr(thorarena_last_error_message());
        assert!(message.to_str().unwrap().contains("client is NULL"));
    }
}

#[test]
fn a_connect_without_joints_says_which_argument_is_wrong() {
    let mut options = std::mem::MaybeUninit::uninit();
    let mut out = std::ptr::null_mut();
    // SAFETY: `options` is filled by the default function before it is read.
    unsafe {
        assert_eq!(
            thorarena_connect_options_default(options.as_mut_ptr()),
            ThorarenaStatus::Ok
        );
        let mut options = options.assume_init();
        options.session = c"ffi-unit".as_ptr();
        assert_eq!(
            thorarena_connect(&options, &mut out),
            ThorarenaStatus::InvalidArgument
        );
        let message = CStr::from_ptr(thorarena_last_error_message());
        assert!(
            message.to_str().unwrap().contains("n_joints"),
            "{message:?}"
        );
    }
}

/// Connects through the C ABI (on the calling thread) to a session of `n_joints`
/// joints named `j0…`, asking for one reference frame.
fn connect(session: &str, n_joints: usize) -> (ThorarenaStatus, *mut ThorarenaClient) {
    let session = CString::new(session).unwrap();
    let names: Vec<CString> = (0..n_joints)
        .map(|i| CString::new(format!("j{i}")).unwrap())
        .collect();
    let name_ptrs: Vec<*const c_char> = names.iter().map(|n| n.as_ptr()).collect();
    let offsets = [0.0];
    let mut options = std::mem::MaybeUninit::uninit();
    let mut client = std::ptr::null_mut();
    // SAFETY: `options` is filled before it is read; every pointer in it outlives the
    // call.
    let status = unsafe {
        thorarena_connect_options_default(options.as_mut_ptr());
        let mut options = options.assume_init();
        options.session = session.as_ptr();
        options.joint_names = name_ptrs.as_ptr();
        options.n_joints = n_joints;
        options.reference_offsets_s = offsets.as_ptr();
        options.n_reference_offsets = 1;
        thorarena_connect(&options, &mut client)
    };
    (status, client)
}

#[test]
fn steps_round_trip_through_the_c_abi_and_misuse_gets_a_typed_status() {
    use crate::{EnvHeader, SimConfig, SimSession, StepOutcome, FLAG_ACTIVE};
    let session = format!("ffi-unit-{}", std::process::id());
    let mut sim = SimSession::create(SimConfig {
        session: session.clone(),
        n_envs: 2,
        joint_names: (0..3).map(|i| format!("j{i}")).collect(),
        control_dt_s: 0.02,
        action_offset_rad: vec![0.0; 3],
        action_scale: vec![1.0; 3],
        budget: None,
        wait: Default::default(),
        inputs: vec![],
    })
    .unwrap();
    let policy = std::thread::spawn(move || {
        let (status, c) = connect(&session, 3);
        assert_eq!(status, ThorarenaStatus::Ok);
        // SAFETY: `c` is a live handle used on this thread (and, on purpose, once on
        // another, which the library refuses without touching it); every output
        // pointer is a local.
        unsafe {
            let mut info = std::mem::MaybeUninit::uninit();
            assert_eq!(
                thorarena_session_info(c, info.as_mut_ptr()),
                ThorarenaStatus::Ok
            );
            let info = info.assume_init();
            assert_eq!((info.n_envs, info.n_joints, info.n_refs), (2, 3, 1));
            assert_eq!(*info.action_scale.add(2), 1.0);
            let (mut q_offset, mut q_len) = (0usize, 0usize);
            assert_eq!(
                thorarena_env_field(c, c"q".as_ptr(), &mut q_offset, &mut q_len),
                ThorarenaStatus::Ok
            );
            assert_eq!(q_len, 3);
            assert_eq!(thorarena_send(c), ThorarenaStatus::CallOrder);
            let address = c as usize;
            let elsewhere = std::thread::spawn(move || {
                let (mut o, mut a) = (std::ptr::null(), std::ptr::null_mut());
                thorarena_next_step(address as *mut ThorarenaClient, 0, &mut o, &mut a)
            });
            assert_eq!(elsewhere.join().unwrap(), ThorarenaStatus::WrongThread);

            let mut steps = 0;
            loop {
                let (mut obs, mut act) = (std::ptr::null(), std::ptr::null_mut());
                match thorarena_next_step(c, THORARENA_WAIT_FOREVER, &mut obs, &mut act) {
                    ThorarenaStatus::Ok => {}
                    ThorarenaStatus::End => break,
                    other => panic!("{other:?}"),
                }
                let (mut o2, mut a2) = (std::ptr::null(), std::ptr::null_mut());
                assert_eq!(
                    thorarena_next_step(c, 0, &mut o2, &mut a2),
                    ThorarenaStatus::CallOrder
                );
                assert!(o2.is_null() && a2.is_null());
                let header = obs.cast::<crate::BatchHeader>().read();
                assert_eq!(header.n_envs, 2);
                for i in 0..2 {
                    let block = obs
                        .add(std::mem::size_of::<crate::BatchHeader>())
                        .add(i * info.env_stride);
                    let q = block.add(q_offset).cast::<f64>();
                    for j in 0..3 {
                        *act.add(i * 3 + j) = 2.0 * *q.add(j);
                    }
                }
                assert_eq!(thorarena_send(c), ThorarenaStatus::Ok);
                steps += 1;
            }
            let (mut obs, mut act) = (std::ptr::null(), std::ptr::null_mut());
            assert_eq!(
                thorarena_next_step(c, 0, &mut obs, &mut act),
                ThorarenaStatus::End,
                "the end stays the end"
            );
            thorarena_close(c);
            steps
        }
    });
    sim.accept(Some(Duration::from_secs(10)), |m| panic!("refused: {m}"))
        .unwrap();
    for step in 0..5u64 {
        let mut got = Vec::new();
        let outcome = sim
            .step(
                |batch| {
                    for i in 0..2 {
                        let mut env = batch.env(i);
                        env.set_header(&EnvHeader {
                            episode_id: i as u64,
                            step,
                            flags: FLAG_ACTIVE,
                            reserved: 0,
                            time_s: 0.0,
                        });
                        for (j, q) in env.array("q").iter_mut().enumerate() {
                            *q = (step * 100 + i as u64 * 10 + j as u64) as f64;
                        }
                    }
                },
                None,
                |actions| got = (0..2).map(|i| actions.env(i).to_vec()).collect(),
            )
            .unwrap();
        assert_eq!(outcome, StepOutcome::Answered);
        for (i, action) in got.iter().enumerate() {
            let want: Vec<f64> = (0..3)
                .map(|j| 2.0 * (step * 100 + i as u64 * 10 + j) as f64)
                .collect();
            assert_eq!(action, &want);
        }
    }
    sim.end();
    assert_eq!(policy.join().unwrap(), 5);
}

#[test]
fn a_refused_connect_returns_the_refusal_status_and_message() {
    use crate::{SimConfig, SimSession};
    let session = format!("ffi-refused-{}", std::process::id());
    let mut sim = SimSession::create(SimConfig {
        session: session.clone(),
        n_envs: 1,
        joint_names: (0..4).map(|i| format!("j{i}")).collect(),
        control_dt_s: 0.02,
        action_offset_rad: vec![0.0; 4],
        action_scale: vec![1.0; 4],
        budget: None,
        wait: Default::default(),
        inputs: vec![],
    })
    .unwrap();
    let policy = std::thread::spawn(move || {
        let (status, c) = connect(&session, 3);
        assert!(c.is_null());
        // SAFETY: the library's own NUL-terminated string.
        let message = unsafe { CStr::from_ptr(thorarena_last_error_message()) };
        (status, message.to_string_lossy().into_owned())
    });
    let start = std::time::Instant::now();
    while !policy.is_finished() && start.elapsed() < Duration::from_secs(20) {
        let _ = sim.accept(Some(Duration::from_millis(50)), |_| {});
    }
    let (status, message) = policy.join().unwrap();
    assert_eq!(status, ThorarenaStatus::RefusedJointCount);
    assert!(
        message.contains("3 joints but the robot has 4"),
        "{message}"
    );
}
