#pragma once
// Internal: what the session reader and writer agree on (sessions/FORMAT.md).
#include <string>
#include <vector>

namespace inhand {

constexpr int kSessionFormatVersion = 1;  // session.json's "version"
// A pose's columns in camera.csv and groundtruth.csv: position [m], quaternion (w first).
inline const std::vector<std::string> kPoseColumns = {"px", "py", "pz", "qw", "qx", "qy", "qz"};

}  // namespace inhand
