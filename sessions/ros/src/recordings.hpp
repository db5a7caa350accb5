#pragma once
// The readers behind OpenRecording. Internal.
#include <memory>
#include <string>

#include "inhand/ros/recording.hpp"

namespace inhand::ros {

std::unique_ptr<Recording> OpenMcap(const std::string& path);
std::unique_ptr<Recording> OpenDb3(const std::string& path);
std::unique_ptr<Recording> OpenRos1Bag(const std::string& path);

}  // namespace inhand::ros
