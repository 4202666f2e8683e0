// The latency-benchmark echo: answer each step with each slot's joint positions (action = q).
//
// Options for failure tests: `--die-after-steps N` kills this process (SIGKILL, no cleanup)
// after answering N steps, on receiving step N + 1; `--delay-ms X --delay-at-step K` sleeps
// X ms before answering step K (1-based), for late-reply tests. Prints "connected" on stdout
// once connected, so a driver can synchronise.
//
//     echo_policy --session NAME [--name echo-cpp] [--timeout S] [--spin-us U]
//                 [--die-after-steps N] [--delay-ms X --delay-at-step K]
#include <chrono>
#include <cinttypes>
#include <csignal>
#include <cstdio>
#include <thread>

#include "example_args.hpp"
#include "thorarena.hpp"

int main(int argc, char** argv) {
    example::Args args(argc, argv,
                       "usage: echo_policy --session NAME [--name NAME] [--timeout S] [--spin-us U] [--profile NAME|none]\n"
                       "                   [--die-after-steps N] [--delay-ms X --delay-at-step K]");
    thorarena::ConnectOptions options;
    options.session = args.str("session");
    options.name = args.str("name", "echo-cpp");
    options.joint_names = example::g1_joint_names();
    options.reference_offsets_s = {0.0};
    // The profile this policy runs under, declared at connect ("none": declare none, so the
    // run must name one with --profile).
    const std::string profile = args.str("profile", "default");
    if (profile != "none") options.profile_name = profile;
    options.timeout = std::chrono::milliseconds(static_cast<long>(1000 * args.num("timeout", 10.0)));
    options.spin = std::chrono::microseconds(static_cast<long>(args.num("spin-us", 50.0)));
    const long die_after = static_cast<long>(args.num("die-after-steps", -1));
    const double delay_ms = args.num("delay-ms", 0.0);
    const long delay_at = static_cast<long>(args.num("delay-at-step", -1));
    try {
        thorarena::Client client(options);
        std::printf("connected\n");
        std::fflush(stdout);
        const thorarena::Field q = client.field("q");
        long step = 0;
        std::uint64_t steps = client.run([&](thorarena::Client& c) {
            ++step;
            if (die_after >= 0 && step == die_after + 1) {
                // Step N's actions went out; die holding step N + 1.
                std::raise(SIGKILL);
            }
            if (step == delay_at && delay_ms > 0) {
                std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(delay_ms));
            }
            for (std::size_t i = 0; i < c.n_envs(); ++i) {
                thorarena::Span<const double> from = c.env(i)[q];
                thorarena::Span<double> to = c.actions(i);
                for (std::size_t j = 0; j < to.size(); ++j) to[j] = from[j];
            }
        });
        std::printf("run over after %" PRIu64 " steps\n", steps);
        return 0;
    } catch (const thorarena::Error& e) {
        std::fprintf(stderr, "echo_policy: %s\n", e.what());
        return 1;
    }
}
