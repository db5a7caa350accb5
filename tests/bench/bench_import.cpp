// inhand import of a ROS 1 bag with 10 s of 500 Hz joint states (16 hand + 7 arm joints) and
// 30 Hz 640x480 rgb8 images with TF: target >= 20x real time (the recording's 10 s in <= 0.5 s).
#include <benchmark/benchmark.h>
#include <geometry_msgs/TransformStamped.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <tf2_msgs/TFMessage.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "bench_paths.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/ros/import.hpp"
#include "inhand/sessions/image_io.hpp"

namespace {

const std::string kHand = inhand::kRoot + "/assets/hands/inhand_hand/inhand_hand.urdf";
constexpr double kSeconds = 10.0;

// A camera-like picture: smooth shading, edges, sensor noise (PNG cannot squeeze it to nothing).
std::vector<std::uint8_t> Picture(int f, std::mt19937& rng) {
  std::vector<std::uint8_t> data(640 * 480 * 3);
  std::normal_distribution<double> noise(0.0, 2.0);
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 640; ++x) {
      const bool inside = std::hypot(x - 320 - 3 * f, y - 240) < 120;
      for (int c = 0; c < 3; ++c) {
        const double v = (inside ? 180 : 60) + 40 * std::sin(0.01 * x + c) +
                         30 * std::cos(0.013 * y) + noise(rng);
        data[(static_cast<std::size_t>(y) * 640 + x) * 3 + c] =
            static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
      }
    }
  return data;
}

// The 268 MB bag, written once per process and removed at exit.
struct TempFile {
  std::string path;
  ~TempFile() {
    std::error_code ec;
    std::filesystem::remove(path, ec);
  }
};

const std::string& Recording() {
  static const TempFile file{[] {
    const std::string p = (std::filesystem::temp_directory_path() /
                           ("inhand-bench-import-" + std::to_string(::getpid()) + ".bag"))
                              .string();
    const std::vector<std::string> names = inhand::LoadHandModel(kHand, {{}, false}).QNames();
    rosbag::Bag bag(p, rosbag::bagmode::Write);
    const ros::Time base(1700000000, 0);
    std::mt19937 rng(7);
    for (int k = 0; k < static_cast<int>(kSeconds * 500); ++k) {
      sensor_msgs::JointState m;
      m.header.stamp = base + ros::Duration(k * 0.002);
      for (int a = 0; a < 7; ++a)
        m.name.push_back("arm_" + std::to_string(a)), m.position.push_back(0.1 * a),
            m.effort.push_back(1.0);
      for (std::size_t j = 0; j < names.size(); ++j)
        m.name.push_back(names[j]), m.position.push_back(0.2 + 0.1 * std::sin(0.01 * k + j)),
            m.effort.push_back(0.05 * j);
      bag.write("/joint_states", m.header.stamp, m);
      if (k % 5 == 0) {
        tf2_msgs::TFMessage tf;
        geometry_msgs::TransformStamped t;
        t.header.stamp = m.header.stamp;
        t.header.frame_id = "palm";
        t.child_frame_id = "camera";
        t.transform.translation.x = 0.3 + 1e-4 * k;
        t.transform.rotation.w = 1.0;
        tf.transforms.push_back(t);
        bag.write("/tf", m.header.stamp, tf);
      }
    }
    for (int f = 0; f < static_cast<int>(kSeconds * 30); ++f) {
      sensor_msgs::Image img;
      img.header.stamp = base + ros::Duration(0.001 + f / 30.0);
      img.header.frame_id = "camera";
      img.height = 480, img.width = 640, img.encoding = "rgb8", img.step = 640 * 3;
      img.data = Picture(f, rng);
      bag.write("/camera/image_raw", img.header.stamp, img);
      sensor_msgs::CameraInfo info;
      info.header = img.header;
      info.width = 640, info.height = 480;
      info.K = {525, 0, 319.5, 0, 525, 239.5, 0, 0, 1};
      bag.write("/camera/camera_info", img.header.stamp, info);
    }
    bag.close();
    return p;
  }()};
  return file.path;
}

void BM_Import_Ros1Bag_10s_500HzJoints_30Hz640x480(benchmark::State& state) {
  const std::string out = (std::filesystem::temp_directory_path() /
                           ("inhand-bench-import-session-" + std::to_string(::getpid())))
                              .string();
  inhand::ros::ImportOptions o;
  o.recording = Recording();
  o.out = out;
  o.overwrite = true;
  o.hand_urdf = kHand;
  o.object = inhand::kRoot + "/assets/objects/ketchup_bottle/object.json";
  o.effort_is_external = true;
  o.initial_pose = inhand::Transform::Identity();
  std::uint64_t frames = 0;
  for (auto _ : state) frames = inhand::ros::ImportRecording(o).frames;
  state.counters["frames"] = static_cast<double>(frames);
  // Recorded seconds per wall second (the target is >= 20).
  state.counters["x_real_time"] = benchmark::Counter(
      kSeconds * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  std::filesystem::remove_all(out);
}

// The importer's lossless PNG of one camera frame (Sub filter + Huffman-only deflate).
void BM_EncodePng_640x480(benchmark::State& state) {
  std::mt19937 rng(3);
  const std::vector<std::uint8_t> pixels = Picture(0, rng);
  std::size_t bytes = 0;
  for (auto _ : state) bytes = inhand::EncodePng(pixels.data(), 640, 480, 3, 640 * 3).size();
  state.counters["compressed_fraction"] =
      static_cast<double>(bytes) / static_cast<double>(pixels.size());
}

}  // namespace

BENCHMARK(BM_EncodePng_640x480)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Import_Ros1Bag_10s_500HzJoints_30Hz640x480)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);
