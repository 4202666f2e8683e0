// The cross-language example scenario "replay": answer each step with the action that makes
// the PD target equal the first reference frame's joint positions.
//
//     action = (reference[0].joint_pos - action_offset_rad) / action_scale   (active slots)
//     action = 0                                                             (inactive slots)
//
// Run it against a ThorArena run serving session NAME:
//
//     replay_policy --session NAME [--name replay-cpp] [--timeout S] [--profile default]
//
// Exit status: 0 when the run ended; 1 with the typed status on stderr when the session
// was refused or failed (e.g. "THORARENA_STATUS_REFUSED_JOINT_COUNT").
#include <chrono>
#include <cinttypes>
#include <cstdio>

#include "example_args.hpp"
#include "thorarena.hpp"

int main(int argc, char** argv) {
    example::Args args(argc, argv,
                       "usage: replay_policy --session NAME [--name NAME] [--timeout S] [--profile NAME|none]");
    thorarena::ConnectOptions options;
    options.session = args.str("session");
    options.name = args.str("name", "replay-cpp");
    options.joint_names = example::g1_joint_names();
    options.reference_offsets_s = {0.0};
    // The profile this policy runs under, declared at connect ("none": declare none, so the
    // run must name one with --profile).
    const std::string profile = args.str("profile", "default");
    if (profile != "none") options.profile_name = profile;
    options.timeout = std::chrono::milliseconds(static_cast<long>(1000 * args.num("timeout", 10.0)));
    try {
        thorarena::Client client(options);
        std::printf("connected: %zu environments, %zu joints\n", client.n_envs(), client.n_joints());
        std::fflush(stdout);
        const thorarena::Field target = client.reference_field(0, "joint_pos");
        const auto offset = client.action_offset_rad();
        const auto scale = client.action_scale();
        std::uint64_t steps = client.run([&](thorarena::Client& c) {
            for (std::size_t i = 0; i < c.n_envs(); ++i) {
                thorarena::EnvView env = c.env(i);
                thorarena::Span<double> action = c.actions(i);
                if (!env.active()) {
                    for (double& a : action) a = 0.0;
                    continue;
                }
                thorarena::Span<const double> joint_pos = env[target];
                for (std::size_t j = 0; j < action.size(); ++j) {
                    action[j] = (joint_pos[j] - offset[j]) / scale[j];
                }
            }
        });
        std::printf("run over after %" PRIu64 " steps\n", steps);
        return 0;
    } catch (const thorarena::Error& e) {
        std::fprintf(stderr, "replay_policy: %s\n", e.what());
        return 1;
    }
}
