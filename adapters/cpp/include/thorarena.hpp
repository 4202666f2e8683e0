// thorarena.hpp: a header-only C++17 wrapper over the ThorArena C ABI (thorarena.h, the
// Rust policy client in crate thorarena-ipc): an RAII client, a typed exception carrying
// the status, and spans over the observation and action arrays in shared memory.
//
//   thorarena::ConnectOptions options;
//   options.session = "demo";
//   options.joint_names = {...};             // the policy's joint order
//   thorarena::Client client(options);       // throws thorarena::Error (e.g. a refusal)
//   thorarena::Field q = client.field("q");
//   client.run([&](thorarena::Client& c) {   // until the simulator ends the run
//       for (std::size_t i = 0; i < c.n_envs(); ++i) {
//           auto env = c.env(i);
//           auto action = c.actions(i);      // zeroed, n_joints doubles
//           if (env.active()) std::copy(env[q].begin(), env[q].end(), action.begin());
//       }
//   });
//
// A Client wraps iceoryx2 ports bound to their thread: use it on the thread that made it.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "thorarena.h"

namespace thorarena {

/// A failed call of the C ABI: the typed status and the library's message.
class Error : public std::runtime_error {
public:
    Error(ThorarenaStatus status, const std::string& what)
        : std::runtime_error(what), status_(status) {}

    /// The status the C ABI returned.
    ThorarenaStatus status() const noexcept { return status_; }

    /// Its C name, e.g. "THORARENA_STATUS_REFUSED_JOINT_COUNT".
    const char* status_name() const noexcept { return thorarena_status_name(status_); }

private:
    ThorarenaStatus status_;
};

/// Throws an Error for anything but THORARENA_STATUS_OK: "<status name>: <message>" (the
/// library's message starts with the failing call).
inline void check(ThorarenaStatus status) {
    if (status == THORARENA_STATUS_OK) return;
    throw Error(status, std::string(thorarena_status_name(status)) + ": " +
                            thorarena_last_error_message());
}

/// A view of `size` contiguous elements (std::span is C++20).
template <class T>
class Span {
public:
    Span() = default;
    Span(T* data, std::size_t size) : data_(data), size_(size) {}
    T* data() const noexcept { return data_; }
    std::size_t size() const noexcept { return size_; }
    T& operator[](std::size_t i) const noexcept { return data_[i]; }
    T* begin() const noexcept { return data_; }
    T* end() const noexcept { return data_ + size_; }

private:
    T* data_ = nullptr;
    std::size_t size_ = 0;
};

/// Where a named f64 array sits in an environment block: byte offset and length.
struct Field {
    std::size_t offset = 0;
    std::size_t len = 0;
};

/// One environment's block of the observation batch (read-only, in shared memory).
class EnvView {
public:
    explicit EnvView(const std::uint8_t* block) : block_(block) {}

    /// The block header (copied out).
    ThorarenaEnvHeader header() const noexcept {
        ThorarenaEnvHeader h;
        std::memcpy(&h, block_, sizeof h);
        return h;
    }

    /// True when the slot carries a live episode; inactive slots are padding.
    bool active() const noexcept { return (header().flags & THORARENA_FLAG_ACTIVE) != 0; }

    /// The array at `field` (from Client::field); blocks are 8-byte aligned.
    Span<const double> operator[](const Field& field) const noexcept {
        return {reinterpret_cast<const double*>(block_ + field.offset), field.len};
    }

private:
    const std::uint8_t* block_;
};

/// A dynamics profile by its numbers: what a policy was trained under. Each vector holds
/// one value per joint, in the robot's canonical order.
struct Profile {
    std::string name;                 ///< its name, for results (at most 31 bytes)
    double control_dt_s = 0.02;       ///< control period, s
    double physics_dt_s = 0.005;      ///< physics step, s (divides control_dt_s)
    std::uint32_t action_delay_steps = 0;  ///< control steps between an action and its effect
    double action_clip = 0.0;         ///< raw actions clipped to +-this before scaling (0: none)
    std::vector<double> kp;           ///< PD stiffness, N m/rad
    std::vector<double> kd;           ///< PD damping, N m s/rad
    std::vector<double> action_scale;       ///< target = offset + scale * action
    std::vector<double> action_offset_rad;  ///< the action offset (default pose), rad
};

/// What a policy declares when it connects.
struct ConnectOptions {
    std::string session;                                   ///< session to join
    std::string name = "cpp";                              ///< name recorded in the results
    std::vector<std::string> joint_names;                  ///< the policy's joint order
    std::vector<double> reference_offsets_s{0.0};          ///< reference frames wanted, s ahead
    std::chrono::milliseconds timeout{10000};              ///< wait for the simulator
    std::chrono::microseconds spin{50};                    ///< busy-poll before blocking
    std::uint32_t protocol_version = 0;                    ///< 0: the library's
    std::string input;                                     ///< a network input the simulator builds ("twist2"), or none
    /// The profile the policy was trained under, by a bundled profile's name ("default",
    /// "wbc-mjlab"); empty: `profile` below, or none. A run that names no profile runs
    /// under the declared one; one whose --profile contradicts it refuses the policy;
    /// with neither, the policy is refused (THORARENA_STATUS_REFUSED_PROFILE).
    std::string profile_name;
    /// The profile by its numbers (used when `profile_name` is empty and `name` is set).
    Profile profile;
};

/// What waiting for a step gave.
enum class Next { Step, End, Timeout };

/// `timeout` of Client::next_step: wait as long as the simulator lives.
inline constexpr std::chrono::microseconds wait_forever{THORARENA_WAIT_FOREVER};

/// A connected policy (move-only; closes the session when destroyed).
class Client {
public:
    /// Connects; throws Error (a refusal carries THORARENA_STATUS_REFUSED_*).
    explicit Client(const ConnectOptions& options) {
        std::vector<const char*> names;
        names.reserve(options.joint_names.size());
        for (const auto& n : options.joint_names) names.push_back(n.c_str());
        ThorarenaConnectOptions o;
        check(thorarena_connect_options_default(&o));
        o.session = options.session.c_str();
        o.policy_name = options.name.c_str();
        o.joint_names = names.data();
        o.n_joints = names.size();
        o.reference_offsets_s = options.reference_offsets_s.data();
        o.n_reference_offsets = options.reference_offsets_s.size();
        o.timeout_ms = static_cast<std::uint64_t>(options.timeout.count());
        o.spin_us = static_cast<std::uint64_t>(options.spin.count());
        o.protocol_version = options.protocol_version;
        o.input = options.input.c_str();
        ThorarenaProfile p{};
        if (!options.profile_name.empty()) {
            o.profile_name = options.profile_name.c_str();
        } else if (!options.profile.name.empty()) {
            const Profile& d = options.profile;
            for (const auto* v : {&d.kp, &d.kd, &d.action_scale, &d.action_offset_rad}) {
                if (v->size() != names.size())
                    throw Error(THORARENA_STATUS_INVALID_ARGUMENT,
                                "profile " + d.name + ": a per-joint vector has " +
                                    std::to_string(v->size()) + " values for " +
                                    std::to_string(names.size()) + " joints");
            }
            p.name = d.name.c_str();
            p.control_dt_s = d.control_dt_s;
            p.physics_dt_s = d.physics_dt_s;
            p.action_delay_steps = d.action_delay_steps;
            p.action_clip = d.action_clip;
            p.kp = d.kp.data();
            p.kd = d.kd.data();
            p.action_scale = d.action_scale.data();
            p.action_offset_rad = d.action_offset_rad.data();
            o.profile = &p;
        }
        check(thorarena_connect(&o, &client_));
        check(thorarena_session_info(client_, &info_));
    }

    ~Client() { thorarena_close(client_); }
    Client(const Client&) = delete;
    Client& operator=(const Client&) = delete;
    Client(Client&& other) noexcept { swap(other); }
    Client& operator=(Client&& other) noexcept {
        if (this != &other) {
            thorarena_close(client_);
            client_ = nullptr;
            swap(other);
        }
        return *this;
    }

    /// The session: shape, sizes, control period, budget, action mapping.
    const ThorarenaSessionInfo& info() const noexcept { return info_; }
    std::size_t n_envs() const noexcept { return info_.n_envs; }
    std::size_t n_joints() const noexcept { return info_.n_joints; }

    /// Action mapping: PD target = offset + scale * action, rad.
    Span<const double> action_offset_rad() const noexcept { return {info_.action_offset_rad, info_.n_joints}; }
    Span<const double> action_scale() const noexcept { return {info_.action_scale, info_.n_joints}; }

    /// A named array of the environment block ("q", "reference[0].joint_pos", ...).
    Field field(const std::string& name) const {
        Field f;
        check(thorarena_env_field(client_, name.c_str(), &f.offset, &f.len));
        return f;
    }

    /// A named array of reference frame `i` ("joint_pos", "root_pos_w", ...).
    Field reference_field(std::size_t i, const std::string& name) const {
        return field("reference[" + std::to_string(i) + "]." + name);
    }

    /// Waits for the next batch; throws Error on failure (e.g. the simulator died).
    Next next_step(std::chrono::microseconds timeout = wait_forever) {
        ThorarenaStatus s = thorarena_next_step(client_, timeout.count(), &obs_, &actions_);
        if (s == THORARENA_STATUS_END) return Next::End;
        if (s == THORARENA_STATUS_TIMEOUT) return Next::Timeout;
        check(s);
        return Next::Step;
    }

    /// The held batch's header (after next_step gave Next::Step, until send).
    ThorarenaBatchHeader batch_header() const noexcept {
        ThorarenaBatchHeader h;
        std::memcpy(&h, obs_, sizeof h);
        return h;
    }

    /// Environment slot `i` of the held batch.
    EnvView env(std::size_t i) const noexcept {
        return EnvView(obs_ + sizeof(ThorarenaBatchHeader) + i * info_.env_stride);
    }

    /// The held batch's policy-input block: n_envs x info().n_inputs floats, row-major, the
    /// network input the simulator built (empty when ConnectOptions::input was empty).
    Span<const float> policy_inputs() const noexcept {
        return {reinterpret_cast<const float*>(obs_ + info_.inputs_offset), info_.n_envs * info_.n_inputs};
    }

    /// The action slot of environment `i` (zeroed on arrival), to fill before send.
    Span<double> actions(std::size_t i) noexcept { return {actions_ + i * info_.n_joints, info_.n_joints}; }

    /// All action slots, n_envs x n_joints, row-major.
    Span<double> all_actions() noexcept { return {actions_, info_.n_envs * info_.n_joints}; }

    /// Sends the actions; the batch views are invalid afterwards.
    void send() {
        check(thorarena_send(client_));
        obs_ = nullptr;
        actions_ = nullptr;
        ++steps_answered_;
    }

    /// Steps answered so far.
    std::uint64_t steps_answered() const noexcept { return steps_answered_; }

    /// Answers every step with `act(*this)` until the run ends; returns the steps answered.
    template <class Act>
    std::uint64_t run(Act&& act) {
        for (;;) {
            Next n = next_step();
            if (n == Next::End) return steps_answered_;
            if (n == Next::Timeout) continue;
            act(*this);
            send();
        }
    }

private:
    void swap(Client& other) noexcept {
        std::swap(client_, other.client_);
        std::swap(info_, other.info_);
        std::swap(obs_, other.obs_);
        std::swap(actions_, other.actions_);
        std::swap(steps_answered_, other.steps_answered_);
    }

    ThorarenaClient* client_ = nullptr;
    ThorarenaSessionInfo info_{};
    const std::uint8_t* obs_ = nullptr;
    double* actions_ = nullptr;
    std::uint64_t steps_answered_ = 0;
};

}  // namespace thorarena
