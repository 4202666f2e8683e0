//! The C ABI over the policy client: connect, take each observation batch straight from
//! shared memory, write the actions into the loaned response, send; typed status codes.
//!
//! Built into `libthorarena_ipc.{so,a}`; the header `ipc/include/thorarena.h` is generated
//! from this file by cbindgen (`ipc/cbindgen.toml`) and checked for drift by
//! `ipc/tests/c_header.rs`. A C or C++ policy does:
//!
//! ```text
//! ThorarenaConnectOptions o; thorarena_connect_options_default(&o);
//! o.session = "demo"; o.joint_names = names; o.n_joints = 29; ...
//! ThorarenaClient *c; if (thorarena_connect(&o, &c) != THORARENA_STATUS_OK) { ... }
//! for (;;) {
//!     const uint8_t *obs; double *act;
//!     ThorarenaStatus s = thorarena_next_step(c, THORARENA_WAIT_FOREVER, &obs, &act);
//!     if (s == THORARENA_STATUS_END) break;
//!     ... read obs (BatchHeader, then n_envs blocks of env_stride bytes), write act ...
//!     thorarena_send(c);
//! }
//! thorarena_close(c);
//! ```
//!
//! Every function returns a [`ThorarenaStatus`] (or nothing) and never unwinds into C: each
//! body runs under `catch_unwind`, a panic becomes [`ThorarenaStatus::Panic`]. The words of
//! the last failure on the calling thread are in [`thorarena_last_error_message`].
//! A client handle wraps iceoryx2 ports that are bound to their thread: use it only on the
//! thread that connected it.

use crate::client::{Next, PolicyClient, PolicyConfig, PolicyStep};
use crate::handshake::{DeclaredProfile, ProfileContent, MAX_JOINTS, MAX_REFERENCE_OFFSETS};
use crate::layout::{Field, Layout};
use crate::session::{IpcError, WaitPolicy};
use crate::PROTOCOL_VERSION;
use std::cell::RefCell;
use std::ffi::{c_char, c_int, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::Duration;

/// `timeout_us` of [`thorarena_next_step`]: wait as long as the simulator lives.
pub const THORARENA_WAIT_FOREVER: i64 = -1;

pub use status::ThorarenaStatus;

/// A failed call: the status to return and the words for `thorarena_last_error_message`.
struct Failure {
    status: ThorarenaStatus,
    message: String,
}

impl From<IpcError> for Failure {
    fn from(error: IpcError) -> Self {
        Self {
            status: ThorarenaStatus::from_error(&error),
            message: error.to_string(),
        }
    }
}

fn invalid(message: impl Into<String>) -> Failure {
    Failure {
        status: ThorarenaStatus::InvalidArgument,
        message: message.into(),
    }
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: &str) {
    let message = CString::new(message.replace('\0', "\\0")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = message);
}

/// Runs one call's body: errors set the thread's last error message, a panic is caught
/// and reported as [`ThorarenaStatus::Panic`] instead of unwinding into C.
fn boundary(
    what: &str,
    body: impl FnOnce() -> Result<ThorarenaStatus, Failure>,
) -> ThorarenaStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(status)) => status,
        Ok(Err(failure)) => {
            set_last_error(&format!("{what}: {}", failure.message));
            failure.status
        }
        Err(panic) => {
            let words = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            set_last_error(&format!("{what}: internal error (panic): {words}"));
            ThorarenaStatus::Panic
        }
    }
}

/// A C string as UTF-8, or an `InvalidArgument` failure naming `what`.
///
/// # Safety
/// `ptr` is NULL or a NUL-terminated string that stays valid for `'a`.
unsafe fn utf8<'a>(ptr: *const c_char, what: &str) -> Result<&'a str, Failure> {
    if ptr.is_null() {
        return Err(invalid(format!("{what} is NULL")));
    }
    // SAFETY: non-NULL and NUL-terminated per this function's contract.
    unsafe { CStr::from_ptr(ptr) }
        .to_str()
        .map_err(|_| invalid(format!("{what} is not UTF-8")))
}

/// How a policy joins a session. Fill it with [`thorarena_connect_options_default`] first,
/// then set the session, the joints and the reference offsets.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ThorarenaConnectOptions {
    /// Session to join (NUL-terminated, `[A-Za-z0-9_.-]{1,64}`).
    pub session: *const c_char,
    /// Name recorded in the results (NUL-terminated UTF-8; NULL: "cpp").
    pub policy_name: *const c_char,
    /// The joint order the policy assumes: `n_joints` NUL-terminated names.
    pub joint_names: *const *const c_char,
    /// Entries of `joint_names`.
    pub n_joints: usize,
    /// Times ahead of each step at which the policy wants reference frames, s.
    pub reference_offsets_s: *const f64,
    /// Entries of `reference_offsets_s` (1 to `THORARENA_MAX_REFERENCE_OFFSETS`).
    pub n_reference_offsets: usize,
    /// How long to wait for the simulator to serve the session and answer, ms.
    pub timeout_ms: u64,
    /// Busy-poll this long before blocking while waiting for a step, µs.
    pub spin_us: u64,
    /// While blocked, check this often that the simulator lives, µs (0: the default).
    pub liveness_us: u64,
    /// Protocol version to announce (0: this library's, `THORARENA_PROTOCOL_VERSION`).
    pub protocol_version: u32,
    /// A network input for the simulator to build into each batch (NUL-terminated name,
    /// e.g. "twist2"; NULL or "": none). See `ThorarenaSessionInfo::inputs_offset`.
    pub input: *const c_char,
    /// The dynamics profile the policy was trained under, by the name of one the
    /// simulator bundles (NUL-terminated, e.g. "wbc-mjlab"; NULL: see `profile`).
    pub profile_name: *const c_char,
    /// The dynamics profile the policy was trained under, by its numbers (NULL: see
    /// `profile_name`). With neither, the run must name one (`--profile`) or it
    /// refuses the policy (`THORARENA_STATUS_REFUSED_PROFILE`); give at most one.
    pub profile: *const ThorarenaProfile,
}

/// A dynamics profile by its numbers: what a policy declares it was trained under. Every
/// array holds `n_joints` values in the robot's canonical joint order (the session's).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ThorarenaProfile {
    /// Its name, for results (NUL-terminated, at most 31 bytes).
    pub name: *const c_char,
    /// Control period, s.
    pub control_dt_s: f64,
    /// Physics step, s (divides `control_dt_s`).
    pub physics_dt_s: f64,
    /// Control steps between an action and its effect.
    pub action_delay_steps: u32,
    /// Raw actions are clipped to ±this before scaling (0: no clip).
    pub action_clip: f64,
    /// PD stiffness, N·m/rad.
    pub kp: *const f64,
    /// PD damping, N·m·s/rad.
    pub kd: *const f64,
    /// Target = offset + scale · action.
    pub action_scale: *const f64,
    /// The action offset (the policy's default pose), rad.
    pub action_offset_rad: *const f64,
}

/// The session as the simulator described it, from [`thorarena_session_info`].
///
/// The observation batch is a `ThorarenaBatchHeader` followed by `n_envs` environment
/// blocks of `env_stride` bytes; each block starts with a `ThorarenaEnvHeader`, its `f64`
/// arrays sit at the offsets [`thorarena_env_field`] gives, reference frame `i` starts at
/// `ref_offset + i * ref_stride`. The action slots are `n_envs × n_joints` doubles,
/// row-major. When the policy asked for an input, the batch ends with it: `n_envs ×
/// n_inputs` floats, row-major, at `inputs_offset` bytes from the batch's start.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ThorarenaSessionInfo {
    /// Environment slots per batch.
    pub n_envs: usize,
    /// Joints per environment.
    pub n_joints: usize,
    /// Reference frames per environment.
    pub n_refs: usize,
    /// Control period, s.
    pub control_dt_s: f64,
    /// Latency budget per step, s (0: none, lock-step).
    pub budget_s: f64,
    /// The simulator's process id.
    pub simulator_pid: u32,
    /// Bytes of an observation batch (header included).
    pub obs_bytes: usize,
    /// Bytes of an action batch (header included).
    pub action_bytes: usize,
    /// Bytes of one environment block.
    pub env_stride: usize,
    /// Byte offset of reference frame 0 within an environment block.
    pub ref_offset: usize,
    /// Bytes of one reference frame.
    pub ref_stride: usize,
    /// `float` values per environment in the policy-input block (0: none asked).
    pub n_inputs: usize,
    /// Byte offset of the policy-input block within the observation batch.
    pub inputs_offset: usize,
    /// `n_joints` offsets of the action mapping: target = offset + scale · action, rad.
    /// Owned by the client, valid until `thorarena_close`.
    pub action_offset_rad: *const f64,
    /// `n_joints` scales of the action mapping (see `action_offset_rad`).
    pub action_scale: *const f64,
}

/// A connected policy (opaque). Created by [`thorarena_connect`], freed by
/// [`thorarena_close`]; used only on the thread that created it.
pub struct ThorarenaClient {
    client: PolicyClient,
    /// The step handed out by `thorarena_next_step`, until `thorarena_send`.
    step: Option<Box<PolicyStep>>,
    /// The environment block's named fields, resolved once.
    fields: Vec<Field>,
    /// The simulator said the run is over.
    ended: bool,
    /// The thread that connected (the only one allowed to use the client).
    owner: std::thread::ThreadId,
}

impl ThorarenaClient {
    fn check_thread(&self) -> Result<(), Failure> {
        if std::thread::current().id() == self.owner {
            Ok(())
        } else {
            Err(Failure {
                status: ThorarenaStatus::WrongThread,
                message: "the client was connected on another thread; use it only there".into(),
            })
        }
    }
}

/// Fills `options` with the defaults: no session or joints yet, 10 s connect timeout,
/// 50 µs spin, liveness check every 2 ms, this library's protocol version.
///
/// Arguments: `options`, the struct to fill.
/// Returns `THORARENA_STATUS_OK`, or `THORARENA_STATUS_INVALID_ARGUMENT` if it is NULL.
///
/// # Safety
/// `options` is NULL or points to writable memory for one `ThorarenaConnectOptions`.
#[no_mangle]
pub unsafe extern "C" fn thorarena_connect_options_default(
    options: *mut ThorarenaConnectOptions,
) -> ThorarenaStatus {
    boundary("thorarena_connect_options_default", || {
        if options.is_null() {
            return Err(invalid("options is NULL"));
        }
        let wait = WaitPolicy::default();
        let defaults = ThorarenaConnectOptions {
            session: std::ptr::null(),
            policy_name: std::ptr::null(),
            joint_names: std::ptr::null(),
            n_joints: 0,
            reference_offsets_s: std::ptr::null(),
            n_reference_offsets: 0,
            timeout_ms: 10_000,
            spin_us: wait.spin.as_micros() as u64,
            liveness_us: wait.liveness_every.as_micros() as u64,
            protocol_version: PROTOCOL_VERSION,
            input: std::ptr::null(),
            profile_name: std::ptr::null(),
            profile: std::ptr::null(),
        };
        // SAFETY: non-NULL and writable per the contract; `write` needs no initialised value.
        unsafe { options.write(defaults) };
        Ok(ThorarenaStatus::Ok)
    })
}

/// Joins a session: says hello and waits (up to `options.timeout_ms`) for the simulator's
/// welcome.
///
/// Arguments: `options`, what the policy declares; `out`, receives the client handle
/// (NULL on failure).
/// Returns `THORARENA_STATUS_OK`; a `THORARENA_STATUS_REFUSED_*` status when the simulator
/// refused the handshake (its reason is in `thorarena_last_error_message`);
/// `NO_SESSION` when no simulator served the session in time; `TIMEOUT` when it did not
/// answer; `SESSION_NAME`, `INVALID_ARGUMENT` or `TRANSPORT` otherwise.
///
/// # Safety
/// `options` is NULL or points to a valid `ThorarenaConnectOptions` whose pointers are
/// NULL or valid for their counts (strings NUL-terminated); `out` is NULL or writable.
/// Nothing is kept from `options` after the call returns.
#[no_mangle]
pub unsafe extern "C" fn thorarena_connect(
    options: *const ThorarenaConnectOptions,
    out: *mut *mut ThorarenaClient,
) -> ThorarenaStatus {
    boundary("thorarena_connect", || {
        if out.is_null() {
            return Err(invalid("out is NULL"));
        }
        // SAFETY: `out` is non-NULL and writable per the contract.
        unsafe { out.write(std::ptr::null_mut()) };
        if options.is_null() {
            return Err(invalid("options is NULL"));
        }
        // SAFETY: non-NULL and valid per the contract.
        let o = unsafe { &*options };
        // SAFETY: the string is NULL or NUL-terminated per the contract.
        let session = unsafe { utf8(o.session, "options.session") }?;
        let name = if o.policy_name.is_null() {
            "cpp"
        } else {
            // SAFETY: as for `session`.
            unsafe { utf8(o.policy_name, "options.policy_name") }?
        };
        if o.n_joints == 0 || o.n_joints > MAX_JOINTS {
            return Err(invalid(format!(
                "options.n_joints is {}: 1 to {MAX_JOINTS}",
                o.n_joints
            )));
        }
        if o.joint_names.is_null() {
            return Err(invalid("options.joint_names is NULL"));
        }
        // SAFETY: non-NULL and valid for `n_joints` entries per the contract.
        let raw_names = unsafe { std::slice::from_raw_parts(o.joint_names, o.n_joints) };
        let joint_names = raw_names
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                // SAFETY: each entry is NULL or NUL-terminated per the contract.
                unsafe { utf8(p, &format!("options.joint_names[{i}]")) }.map(String::from)
            })
            .collect::<Result<Vec<_>, _>>()?;
        if o.n_reference_offsets > MAX_REFERENCE_OFFSETS {
            return Err(invalid(format!(
                "options.n_reference_offsets is {}: at most {MAX_REFERENCE_OFFSETS}",
                o.n_reference_offsets
            )));
        }
        let offsets = if o.n_reference_offsets == 0 {
            Vec::new()
        } else if o.reference_offsets_s.is_null() {
            return Err(invalid("options.reference_offsets_s is NULL"));
        } else {
            // SAFETY: non-NULL and valid for `n_reference_offsets` entries per the contract.
            unsafe { std::slice::from_raw_parts(o.reference_offsets_s, o.n_reference_offsets) }
                .to_vec()
        };
        let mut config = PolicyConfig::new(session, name, joint_names, offsets);
        if o.protocol_version != 0 {
            config.protocol_version = o.protocol_version;
        }
        if !o.input.is_null() {
            // SAFETY: as for `session`.
            config.input = unsafe { utf8(o.input, "options.input") }?.to_string();
        }
        // SAFETY: `profile_name` and `profile` are NULL or valid per the contract.
        config.profile = unsafe { declared_profile(o) }?;
        config.wait = WaitPolicy {
            spin: Duration::from_micros(o.spin_us),
            liveness_every: if o.liveness_us == 0 {
                WaitPolicy::default().liveness_every
            } else {
                Duration::from_micros(o.liveness_us)
            },
            ..WaitPolicy::default()
        };
        let client = PolicyClient::connect(&config, Duration::from_millis(o.timeout_ms))?;
        let l = client.info().layout;
        let handle = Box::new(ThorarenaClient {
            fields: l.env_fields(),
            client,
            step: None,
            ended: false,
            owner: std::thread::current().id(),
        });
        // SAFETY: `out` is non-NULL and writable (checked above).
        unsafe { out.write(Box::into_raw(handle)) };
        Ok(ThorarenaStatus::Ok)
    })
}

/// The profile `o` declares: by name, by content, or none.
///
/// # Safety
/// `o.profile_name` is NULL or NUL-terminated; `o.profile` is NULL or valid, its arrays
/// valid for `o.n_joints` values and its name NULL or NUL-terminated.
unsafe fn declared_profile(
    o: &ThorarenaConnectOptions,
) -> Result<Option<DeclaredProfile>, Failure> {
    match (o.profile_name.is_null(), o.profile.is_null()) {
        (true, true) => Ok(None),
        (false, false) => Err(invalid(
            "options.profile_name and options.profile are both set: declare the profile one way",
        )),
        (false, true) => {
            // SAFETY: non-NULL and NUL-terminated per the contract.
            let name = unsafe { utf8(o.profile_name, "options.profile_name") }?;
            Ok(Some(DeclaredProfile::Named(name.to_string())))
        }
        (true, false) => {
            // SAFETY: non-NULL and valid per the contract.
            let p = unsafe { &*o.profile };
            let array = |ptr: *const f64, what: &str| {
                if ptr.is_null() {
                    return Err(invalid(format!("options.profile->{what} is NULL")));
                }
                // SAFETY: non-NULL and valid for `n_joints` values per the contract.
                Ok(unsafe { std::slice::from_raw_parts(ptr, o.n_joints) }.to_vec())
            };
            Ok(Some(DeclaredProfile::Content(ProfileContent {
                // SAFETY: NULL or NUL-terminated per the contract.
                name: unsafe { utf8(p.name, "options.profile->name") }?.to_string(),
                control_dt_s: p.control_dt_s,
                physics_dt_s: p.physics_dt_s,
                action_delay_steps: p.action_delay_steps,
                action_clip: Some(p.action_clip).filter(|c| *c != 0.0),
                kp: array(p.kp, "kp")?,
                kd: array(p.kd, "kd")?,
                action_scale: array(p.action_scale, "action_scale")?,
                action_offset_rad: array(p.action_offset_rad, "action_offset_rad")?,
            })))
        }
    }
}

/// The client behind a handle, or an `InvalidArgument` failure.
///
/// # Safety
/// `client` is NULL or a live handle from `thorarena_connect`, not used elsewhere meanwhile.
unsafe fn handle<'a>(client: *mut ThorarenaClient) -> Result<&'a mut ThorarenaClient, Failure> {
    // SAFETY: NULL or a live, unaliased handle per the contract.
    let c = unsafe { client.as_mut() }.ok_or_else(|| invalid("client is NULL"))?;
    c.check_thread()?;
    Ok(c)
}

/// The client behind a handle for reading, or an `InvalidArgument` failure.
///
/// # Safety
/// `client` is NULL or a live handle from `thorarena_connect`.
unsafe fn handle_ref<'a>(client: *const ThorarenaClient) -> Result<&'a ThorarenaClient, Failure> {
    // SAFETY: NULL or a live handle per the contract.
    let c = unsafe { client.as_ref() }.ok_or_else(|| invalid("client is NULL"))?;
    c.check_thread()?;
    Ok(c)
}

/// Describes the session: batch shape, sizes and offsets, control period, budget and the
/// action mapping.
///
/// Arguments: `client`, a connected client; `out`, receives the description (its two
/// pointers stay valid until `thorarena_close`).
/// Returns `THORARENA_STATUS_OK`, or `THORARENA_STATUS_INVALID_ARGUMENT` on a NULL pointer.
///
/// # Safety
/// `client` is NULL or a live handle from `thorarena_connect`; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn thorarena_session_info(
    client: *const ThorarenaClient,
    out: *mut ThorarenaSessionInfo,
) -> ThorarenaStatus {
    boundary("thorarena_session_info", || {
        // SAFETY: NULL or a live handle per the contract.
        let c = unsafe { handle_ref(client) }?;
        if out.is_null() {
            return Err(invalid("out is NULL"));
        }
        let info = c.client.info();
        let l = info.layout;
        let described = ThorarenaSessionInfo {
            n_envs: l.n_envs,
            n_joints: l.n_joints,
            n_refs: l.n_refs,
            control_dt_s: info.control_dt_s,
            budget_s: info.budget.map_or(0.0, |b| b.as_secs_f64()),
            simulator_pid: info.simulator_pid,
            obs_bytes: l.obs_bytes(),
            action_bytes: l.action_bytes(),
            env_stride: l.env_stride(),
            ref_offset: l.ref_offset(),
            ref_stride: l.ref_stride(),
            n_inputs: l.n_inputs,
            inputs_offset: l.inputs_offset(),
            action_offset_rad: info.action_offset_rad.as_ptr(),
            action_scale: info.action_scale.as_ptr(),
        };
        // SAFETY: non-NULL and writable per the contract.
        unsafe { out.write(described) };
        Ok(ThorarenaStatus::Ok)
    })
}

/// Waits for the next observation batch and loans its action batch.
///
/// Arguments: `client`, a connected client; `timeout_us`, how long to wait, µs
/// (`THORARENA_WAIT_FOREVER` or any negative value: as long as the simulator lives);
/// `obs_batch`, receives the observation batch in shared memory — the whole block,
/// starting with its `ThorarenaBatchHeader` (`obs_bytes` bytes, 8-byte aligned);
/// `actions`, receives the action slots in the loaned response — `n_envs × n_joints`
/// doubles after the action header, zeroed, to be filled before `thorarena_send`.
/// Both pointers are valid until the next `thorarena_send` or `thorarena_close`, and
/// set to NULL unless the call returns OK.
/// Returns `THORARENA_STATUS_OK` (answer it, then call `thorarena_send`);
/// `THORARENA_STATUS_END` when the run is over (again on every later call);
/// `THORARENA_STATUS_TIMEOUT` when nothing came in time; `SIMULATOR_GONE` when the
/// simulator died; `CALL_ORDER` when the previous step was not sent yet; `LAYOUT`,
/// `TRANSPORT` or `INVALID_ARGUMENT` otherwise.
///
/// # Safety
/// `client` is NULL or a live handle from `thorarena_connect` used only on this thread;
/// `obs_batch` and `actions` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn thorarena_next_step(
    client: *mut ThorarenaClient,
    timeout_us: i64,
    obs_batch: *mut *const u8,
    actions: *mut *mut f64,
) -> ThorarenaStatus {
    boundary("thorarena_next_step", || {
        if obs_batch.is_null() || actions.is_null() {
            return Err(invalid("obs_batch or actions is NULL"));
        }
        // SAFETY: both non-NULL and writable per the contract.
        unsafe {
            obs_batch.write(std::ptr::null());
            actions.write(std::ptr::null_mut());
        }
        // SAFETY: NULL or a live handle per the contract.
        let c = unsafe { handle(client) }?;
        if c.step.is_some() {
            return Err(Failure {
                status: ThorarenaStatus::CallOrder,
                message: "the previous step was not sent: call thorarena_send first".into(),
            });
        }
        if c.ended {
            return Ok(ThorarenaStatus::End);
        }
        let timeout = u64::try_from(timeout_us).ok().map(Duration::from_micros);
        match c.client.next_step(timeout)? {
            Next::Step(mut step) => {
                let action_ptr = step.actions()?.all().as_mut_ptr();
                let obs_ptr = step.observations().bytes().as_ptr();
                // The pointers stay valid while `step` (and so the request and the loaned
                // response in shared memory) lives in the handle; moving the box does not
                // move the shared memory.
                c.step = Some(step);
                // SAFETY: both non-NULL and writable per the contract.
                unsafe {
                    obs_batch.write(obs_ptr);
                    actions.write(action_ptr);
                }
                Ok(ThorarenaStatus::Ok)
            }
            Next::End => {
                c.ended = true;
                Ok(ThorarenaStatus::End)
            }
            Next::Timeout => Ok(ThorarenaStatus::Timeout),
        }
    })
}

/// Sends the actions written into the slots `thorarena_next_step` gave and wakes the
/// simulator. The observation and action pointers are invalid afterwards.
///
/// Arguments: `client`, a connected client holding a step.
/// Returns `THORARENA_STATUS_OK` (also when the simulator already gave up on this step:
/// a late reply is counted there, not an error here); `CALL_ORDER` when no step is held;
/// `TRANSPORT` or `INVALID_ARGUMENT` otherwise.
///
/// # Safety
/// `client` is NULL or a live handle from `thorarena_connect` used only on this thread.
#[no_mangle]
pub unsafe extern "C" fn thorarena_send(client: *mut ThorarenaClient) -> ThorarenaStatus {
    boundary("thorarena_send", || {
        // SAFETY: NULL or a live handle per the contract.
        let c = unsafe { handle(client) }?;
        let step = c.step.take().ok_or_else(|| Failure {
            status: ThorarenaStatus::CallOrder,
            message: "no step to send: call thorarena_next_step first".into(),
        })?;
        step.send(&c.client)?;
        Ok(ThorarenaStatus::Ok)
    })
}

/// Leaves the session and frees the client; a step still held is dropped unanswered.
///
/// Arguments: `client`, a handle from `thorarena_connect`, or NULL (nothing happens).
/// Called on another thread than the one that connected, it leaks the client instead of
/// touching its ports there (and sets `thorarena_last_error_message`).
///
/// # Safety
/// `client` is NULL or a live handle from `thorarena_connect`, not used again afterwards.
#[no_mangle]
pub unsafe extern "C" fn thorarena_close(client: *mut ThorarenaClient) {
    if client.is_null() {
        return;
    }
    boundary("thorarena_close", || {
        // SAFETY: a live handle made by `Box::into_raw` in `thorarena_connect`, given back
        // exactly once per the contract.
        let c = unsafe { Box::from_raw(client) };
        if let Err(failure) = c.check_thread() {
            std::mem::forget(c);
            return Err(failure);
        }
        drop(c);
        Ok(ThorarenaStatus::Ok)
    });
}

/// Byte offset and length of a named `f64` array within an environment block, resolved
/// against `fields`.
///
/// # Safety
/// `name` is NULL or NUL-terminated; `offset` and `len` are NULL or writable.
unsafe fn find_field(
    fields: &[Field],
    name: *const c_char,
    offset: *mut usize,
    len: *mut usize,
) -> Result<ThorarenaStatus, Failure> {
    if offset.is_null() || len.is_null() {
        return Err(invalid("offset or len is NULL"));
    }
    // SAFETY: NULL or NUL-terminated per the contract.
    let name = unsafe { utf8(name, "name") }?;
    let field = fields.iter().find(|f| f.name == name).ok_or_else(|| {
        invalid(format!(
            "no field {name:?} in this layout; fields are {}",
            fields
                .iter()
                .map(|f| f.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })?;
    // SAFETY: both non-NULL and writable per the contract.
    unsafe {
        offset.write(field.offset);
        len.write(field.len);
    }
    Ok(ThorarenaStatus::Ok)
}

/// Finds a named `f64` array of the session's environment block.
///
/// Arguments: `client`, a connected client; `name`, a field name as in `ipc/layout.json`:
/// `q`, `qd`, `last_action`, `root_pos_w`, … or `reference[i].joint_pos`,
/// `reference[i].time_s`, …; `offset`, receives its byte offset from the start of the
/// environment block (the `ThorarenaEnvHeader`); `len`, receives its number of doubles.
/// Returns `THORARENA_STATUS_OK`, or `THORARENA_STATUS_INVALID_ARGUMENT` for an unknown
/// name (the message lists the valid ones) or a NULL pointer.
///
/// # Safety
/// `client` is NULL or a live handle; `name` is NULL or NUL-terminated; `offset` and
/// `len` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn thorarena_env_field(
    client: *const ThorarenaClient,
    name: *const c_char,
    offset: *mut usize,
    len: *mut usize,
) -> ThorarenaStatus {
    boundary("thorarena_env_field", || {
        // SAFETY: NULL or a live handle per the contract.
        let c = unsafe { handle_ref(client) }?;
        // SAFETY: the pointers' contract is this function's.
        unsafe { find_field(&c.fields, name, offset, len) }
    })
}

/// Finds a named `f64` array of an environment block for any shape, without a session
/// (the same answer as `thorarena_env_field` for a session of that shape).
///
/// Arguments: `n_joints`, joints per environment; `n_refs`, reference frames per
/// environment; `name`, `offset`, `len` as in `thorarena_env_field`.
/// Returns `THORARENA_STATUS_OK`, or `THORARENA_STATUS_INVALID_ARGUMENT` for an unknown
/// name, a NULL pointer, or more than `THORARENA_MAX_JOINTS` joints or
/// `THORARENA_MAX_REFERENCE_OFFSETS` reference frames.
///
/// # Safety
/// `name` is NULL or NUL-terminated; `offset` and `len` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn thorarena_layout_env_field(
    n_joints: usize,
    n_refs: usize,
    name: *const c_char,
    offset: *mut usize,
    len: *mut usize,
) -> ThorarenaStatus {
    boundary("thorarena_layout_env_field", || {
        if n_joints > MAX_JOINTS || n_refs > MAX_REFERENCE_OFFSETS {
            return Err(invalid(format!(
                "{n_joints} joints and {n_refs} reference frames: at most {MAX_JOINTS} and \
                 {MAX_REFERENCE_OFFSETS}"
            )));
        }
        let fields = Layout {
            n_envs: 1,
            n_joints,
            n_refs,
            n_inputs: 0,
        }
        .env_fields();
        // SAFETY: the pointers' contract is this function's.
        unsafe { find_field(&fields, name, offset, len) }
    })
}

/// The words of the last failure on the calling thread (empty if none yet).
///
/// Arguments: none.
/// Returns a NUL-terminated UTF-8 string owned by the library, valid until the next
/// failing call on this thread; never NULL.
///
/// # Safety
/// No preconditions (a safe function); the result must not be freed or written.
#[no_mangle]
pub extern "C" fn thorarena_last_error_message() -> *const c_char {
    catch_unwind(|| LAST_ERROR.with(|e| e.borrow().as_ptr())).unwrap_or(c"".as_ptr())
}

/// The C name of a status (`"THORARENA_STATUS_REFUSED_JOINT_COUNT"`), for messages.
///
/// Arguments: `status`, a `ThorarenaStatus` value (taken as an int, so any value is safe).
/// Returns a static NUL-terminated string; `"THORARENA_STATUS_UNKNOWN"` for a value that
/// is not a status.
///
/// # Safety
/// No preconditions (a safe function); the result must not be freed or written.
#[no_mangle]
pub extern "C" fn thorarena_status_name(status: c_int) -> *const c_char {
    ThorarenaStatus::ALL
        .iter()
        .find(|s| **s as c_int == status)
        .map_or(c"THORARENA_STATUS_UNKNOWN", |s| s.name())
        .as_ptr()
}

/// The protocol version this library speaks (compare with `THORARENA_PROTOCOL_VERSION`
/// of the header you compiled against).
///
/// Arguments: none. Returns the version.
///
/// # Safety
/// No preconditions (a safe function).
#[no_mangle]
pub extern "C" fn thorarena_protocol_version() -> u32 {
    PROTOCOL_VERSION
}

mod status;

#[cfg(test)]
#[path = "ffi_tests.rs"]
mod tests;
