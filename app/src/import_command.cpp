// inhand import: a ROS recording → a session (sessions/ros does the work; this parses options
// and shows progress).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "inhand/app/commands.hpp"
#include "inhand/core/error.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/ros/import.hpp"

namespace inhand::app {

namespace {

std::vector<double> Numbers(const std::string& text, std::size_t n, const std::string& option,
                            const std::string& expected) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string cell;
  while (std::getline(ss, cell, ',')) {
    std::size_t used = 0;
    double x = 0;
    try {
      x = std::stod(cell, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != cell.size() || !std::isfinite(x))
      throw InputError(option + ": '" + cell + "' is not a number; expected " + expected);
    v.push_back(x);
  }
  if (v.size() != n)
    throw InputError(option + ": " + std::to_string(v.size()) + " numbers, expected " + expected);
  return v;
}

}  // namespace

int RunImport(const ImportCommand& cmd) {
  if (cmd.list) {
    std::cout << ros::ListRecording(cmd.recording);
    return 0;
  }
  ros::ImportOptions o;
  o.recording = cmd.recording;
  o.out = cmd.out;
  o.overwrite = cmd.overwrite;
  if (cmd.hand.empty() || cmd.object.empty() || cmd.out.empty())
    throw InputError(
        "import: --out, --hand and --object are required (or --list to see what the recording "
        "holds)");
  o.hand_urdf = cmd.hand;
  o.object = cmd.object;
  PackageMap packages;
  for (const std::string& p : cmd.packages) packages.AddSpec(p);
  o.packages = packages.dirs;
  o.joints_topic = cmd.joints;
  if (cmd.effort_is != "none" && cmd.effort_is != "external")
    throw InputError("--effort-is: '" + cmd.effort_is + "', expected external or none");
  o.effort_is_external = cmd.effort_is == "external";
  o.image_topic = cmd.image;
  o.no_images = cmd.no_images;
  o.camera_info_topic = cmd.camera_info;
  o.palm_frame = cmd.palm_frame;
  o.camera_frame = cmd.camera_frame;
  o.object_pose_topic = cmd.object_pose;
  if (!cmd.initial_pose.empty()) {
    const auto v = Numbers(cmd.initial_pose, 7, "--initial-pose",
                           "x,y,z,qw,qx,qy,qz (metres, unit quaternion; palm frame)");
    const double n = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
    if (std::abs(n - 1.0) > 1e-3)
      throw InputError("--initial-pose: the quaternion (" + std::to_string(v[3]) +
                       ", ...) has norm " + std::to_string(n) + ", expected 1");
    o.initial_pose =
        MakeTransform(Vec3(v[0], v[1], v[2]),
                      Quat(v[3], v[4], v[5], v[6]));  // normalises, as session.json's reader does
  }
  if (!cmd.initial_sigma.empty()) {
    const auto v = Numbers(cmd.initial_sigma, 3, "--initial-sigma", "POS_M,ORIENT_RAD,BIAS_RAD");
    o.initial_sigma = std::array<double, 3>{v[0], v[1], v[2]};
  }
  if (!cmd.joint_stiffness.empty()) {
    if (!o.effort_is_external)
      throw InputError(
          "--joint-stiffness: the correction q - tau / k needs the external torques (--effort-is "
          "external)");
    const std::string expected = "K or NAME=K,...[,*=K], stiffness K > 0 in N m/rad";
    std::stringstream ss(cmd.joint_stiffness);
    std::string cell;
    while (std::getline(ss, cell, ',')) {
      const std::size_t eq = cell.find('=');
      const std::string name = eq == std::string::npos ? "*" : cell.substr(0, eq);
      const std::string value = eq == std::string::npos ? cell : cell.substr(eq + 1);
      const double k = Numbers(value, 1, "--joint-stiffness", expected)[0];
      if (name.empty() || !(k > 0.0))
        throw InputError("--joint-stiffness: '" + cell + "', expected " + expected);
      if (!o.joint_stiffness.emplace(name, k).second)
        throw InputError("--joint-stiffness: '" + name + "' given twice");
    }
    if (o.joint_stiffness.empty())
      throw InputError("--joint-stiffness: empty, expected " + expected);
  }
  o.start_s = cmd.start;
  o.end_s = cmd.end;
  o.time_origin_s = cmd.time_origin;

  const bool tty = ::isatty(STDERR_FILENO) != 0;
  int shown = -1;
  const auto progress = [&](double f) {
    const int pct = static_cast<int>(std::floor(100 * std::min(1.0, std::max(0.0, f))));
    if (!tty || pct == shown) return;
    shown = pct;
    const int bar = pct * 30 / 100;
    std::fprintf(stderr, "\rimport [%.*s%.*s] %3d%%", bar, "##############################",
                 30 - bar, "..............................", pct);
    std::fflush(stderr);
  };
  const ros::ImportReport report = ros::ImportRecording(o, progress);
  if (tty) std::fprintf(stderr, "\r%60s\r", "");
  std::cout << "imported " << cmd.recording << " into " << cmd.out << "\n";
  for (const std::string& line : report.Summary()) std::cout << "  " << line << "\n";
  return 0;
}

}  // namespace inhand::app
