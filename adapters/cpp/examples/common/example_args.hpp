// What the C++ example policies share: the G1's joint order and a tiny `--key value`
// command-line reader (the examples take no other dependencies).
#pragma once

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace example {

/// The Unitree G1 (29 DoF) in canonical order: `data/robots/g1_29dof/robot.toml` `joints`
/// (the end-to-end tests use that file's order for the simulator, so a drift is a refusal).
inline const std::vector<std::string>& g1_joint_names() {
    static const std::vector<std::string> names = {
        "left_hip_pitch_joint",      "left_hip_roll_joint",      "left_hip_yaw_joint",
        "left_knee_joint",           "left_ankle_pitch_joint",   "left_ankle_roll_joint",
        "right_hip_pitch_joint",     "right_hip_roll_joint",     "right_hip_yaw_joint",
        "right_knee_joint",          "right_ankle_pitch_joint",  "right_ankle_roll_joint",
        "waist_yaw_joint",           "waist_roll_joint",         "waist_pitch_joint",
        "left_shoulder_pitch_joint", "left_shoulder_roll_joint", "left_shoulder_yaw_joint",
        "left_elbow_joint",          "left_wrist_roll_joint",    "left_wrist_pitch_joint",
        "left_wrist_yaw_joint",      "right_shoulder_pitch_joint", "right_shoulder_roll_joint",
        "right_shoulder_yaw_joint",  "right_elbow_joint",        "right_wrist_roll_joint",
        "right_wrist_pitch_joint",   "right_wrist_yaw_joint",
    };
    return names;
}

/// `--key value` pairs; exits with a usage message on anything else or a missing value.
class Args {
public:
    Args(int argc, char** argv, const char* usage) : usage_(usage) {
        for (int i = 1; i < argc; ++i) {
            std::string key = argv[i];
            if (key == "--help" || key == "-h") {
                std::printf("%s\n", usage_);
                std::exit(0);
            }
            if (key.rfind("--", 0) != 0 || i + 1 >= argc) fail("bad argument " + key);
            values_[key.substr(2)] = argv[++i];
        }
    }

    /// A required string option.
    std::string str(const std::string& key) const {
        auto it = values_.find(key);
        if (it == values_.end()) fail("missing --" + key);
        return it->second;
    }

    /// An optional string option.
    std::string str(const std::string& key, const std::string& fallback) const {
        auto it = values_.find(key);
        return it == values_.end() ? fallback : it->second;
    }

    /// An optional number (integers included).
    double num(const std::string& key, double fallback) const {
        auto it = values_.find(key);
        if (it == values_.end()) return fallback;
        char* end = nullptr;
        double v = std::strtod(it->second.c_str(), &end);
        if (end == it->second.c_str() || *end != '\0') fail("--" + key + " needs a number");
        return v;
    }

private:
    [[noreturn]] void fail(const std::string& why) const {
        std::fprintf(stderr, "%s\n%s\n", why.c_str(), usage_);
        std::exit(64);
    }

    const char* usage_;
    std::map<std::string, std::string> values_;
};

}  // namespace example
