#include "inhand/ros/import.hpp"

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <sstream>
#include <thread>

#include "inhand/core/error.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/ros/recording.hpp"
#include "inhand/ros/tf_tree.hpp"
#include "inhand/sessions/image_io.hpp"
#include "inhand/sessions/output_folder.hpp"
#include "inhand/sessions/session.hpp"

namespace fs = std::filesystem;

namespace inhand::ros {

namespace {

std::string Join(const std::vector<std::string>& v, std::size_t max = 40) {
  std::string out;
  for (std::size_t i = 0; i < v.size() && i < max; ++i) out += (i ? ", " : "") + v[i];
  if (v.size() > max) out += ", ... (" + std::to_string(v.size()) + " in all)";
  return out;
}

std::string TopicList(const std::vector<TopicInfo>& topics) {
  std::vector<std::string> v;
  for (const TopicInfo& t : topics) v.push_back(t.name + " [" + t.type + "]");
  return Join(v);
}

const TopicInfo* FindTopic(const std::vector<TopicInfo>& topics, const std::string& name) {
  for (const TopicInfo& t : topics)
    if (t.name == name) return &t;
  return nullptr;
}

// The topic the user named (checked to exist and to be of one of `types`), or the only topic of
// those types (`required`: an error when there is none or several).
std::string PickTopic(const std::string& path, const std::vector<TopicInfo>& topics,
                      const std::string& given, const std::string& option,
                      const std::vector<MsgType>& types, const std::string& what, bool required) {
  const auto ok = [&](const TopicInfo& t) {
    return std::find(types.begin(), types.end(), MsgTypeOf(t.type)) != types.end();
  };
  if (!given.empty()) {
    const TopicInfo* t = FindTopic(topics, given);
    if (t == nullptr)
      throw InputError(path + ": " + option + " " + given + ": no such topic; the recording has " +
                       TopicList(topics));
    if (!ok(*t))
      throw InputError(path + ": " + option + " " + given + " is of type " + t->type +
                       ", expected " + what);
    return given;
  }
  std::vector<std::string> candidates;
  for (const TopicInfo& t : topics)
    if (ok(t) && t.count > 0) candidates.push_back(t.name);
  if (candidates.size() == 1) return candidates[0];
  if (candidates.empty()) {
    if (required)
      throw InputError(path + ": no " + what + " topic; the recording has " + TopicList(topics));
    return "";
  }
  throw InputError(path + ": several " + what + " topics (" + Join(candidates) +
                   "); choose one with " + option);
}

std::int64_t StampOf(const Header& h, std::int64_t log_ns) {
  return h.stamp_ns != 0 ? h.stamp_ns : log_ns;
}

Intrinsics IntrinsicsOf(const CameraInfoMsg& m, const std::string& context) {
  Intrinsics K;
  K.width = static_cast<int>(m.width);
  K.height = static_cast<int>(m.height);
  K.fx = m.k[0];
  K.fy = m.k[4];
  K.cx = m.k[2];
  K.cy = m.k[5];
  if (m.k[1] != 0.0)
    throw InputError(context + ": K has a skew term (" + std::to_string(m.k[1]) +
                     "), which inhand's pinhole model does not have");
  const bool zeros = std::all_of(m.d.begin(), m.d.end(), [](double v) { return v == 0.0; });
  if (!zeros) {
    if (m.distortion_model == "plumb_bob" || m.distortion_model == "rational_polynomial") {
      // plumb_bob: k1 k2 t1 t2 k3 (OpenCV's order); rational_polynomial adds k4 k5 k6.
      for (std::size_t i = 5; i < m.d.size(); ++i)
        if (m.d[i] != 0.0)
          throw InputError(context + ": distortion coefficient " + std::to_string(i) + " of " +
                           m.distortion_model +
                           " is not zero; inhand supports plumb_bob (k1, k2, p1, p2, k3)");
      for (std::size_t i = 0; i < 5 && i < m.d.size(); ++i) K.distortion[i] = m.d[i];
    } else {
      throw InputError(context + ": distortion model '" + m.distortion_model +
                       "' is not supported (expected plumb_bob)");
    }
  }
  K.Validate(context);
  return K;
}

// A sensor_msgs/Image as RGB. Throws InputError naming the encoding when it is not supported.
Image8 ToRgb(const ImageMsg& m, const std::string& context) {
  const std::string& e = m.encoding;
  const int w = static_cast<int>(m.width), h = static_cast<int>(m.height);
  int bytes_per_pixel = 0;
  if (e == "rgb8" || e == "bgr8")
    bytes_per_pixel = 3;
  else if (e == "rgba8" || e == "bgra8")
    bytes_per_pixel = 4;
  else if (e == "mono8" || e == "8UC1")
    bytes_per_pixel = 1;
  else if (e == "mono16" || e == "16UC1")
    bytes_per_pixel = 2;
  else
    throw InputError(context + ": image encoding '" + e +
                     "' is not supported (expected rgb8, bgr8, rgba8, bgra8, mono8 or mono16)");
  if (w <= 0 || h <= 0 || m.step < static_cast<std::uint64_t>(w) * bytes_per_pixel ||
      m.data.size() < static_cast<std::uint64_t>(m.step) * (h - 1) +
                          static_cast<std::uint64_t>(w) * bytes_per_pixel)
    throw InputError(context + ": " + std::to_string(m.data.size()) + " bytes do not hold a " +
                     std::to_string(w) + "x" + std::to_string(h) + " " + e +
                     " image with a row step of " + std::to_string(m.step));
  Image8 out(w, h, 3);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* row = m.data.data() + static_cast<std::size_t>(y) * m.step;
    std::uint8_t* o = out.pixel(0, y);
    if (e == "rgb8") {
      std::copy(row, row + 3 * w, o);
    } else if (bytes_per_pixel >= 3) {
      const bool bgr = e[0] == 'b';
      for (int x = 0; x < w; ++x, row += bytes_per_pixel, o += 3)
        o[0] = row[bgr ? 2 : 0], o[1] = row[1], o[2] = row[bgr ? 0 : 2];
    } else if (bytes_per_pixel == 1) {
      for (int x = 0; x < w; ++x, o += 3) o[0] = o[1] = o[2] = row[x];
    } else {
      for (int x = 0; x < w; ++x, o += 3) {
        const int v =
            m.is_bigendian ? row[2 * x] << 8 | row[2 * x + 1] : row[2 * x + 1] << 8 | row[2 * x];
        o[0] = o[1] = o[2] = static_cast<std::uint8_t>((v + 128) / 257);
      }
    }
  }
  return out;
}

struct Encoded {
  std::vector<std::uint8_t> bytes;
  std::string extension;
  int width = 0, height = 0;
};

// The frame's file: raw images as PNG, PNG and JPEG messages as they are (after checking that
// they decode).
Encoded EncodeFrame(const Payload& payload, const std::string& context) {
  if (const auto* raw = std::get_if<ImageMsg>(&payload)) {
    const int w = static_cast<int>(raw->width), h = static_cast<int>(raw->height);
    if (raw->encoding == "rgb8" && w > 0 && h > 0 && raw->step >= raw->width * 3 &&
        raw->data.size() >= std::size_t{raw->step} * raw->height)
      return {EncodePng(raw->data.data(), w, h, 3, raw->step), "png", w,
              h};  // straight from the message
    return {EncodePng(ToRgb(*raw, context)), "png", w, h};
  }
  const auto& c = std::get<CompressedImageMsg>(payload);
  std::string f = c.format;
  std::transform(f.begin(), f.end(), f.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  const bool png = f.find("png") != std::string::npos,
             jpeg = f.find("jpeg") != std::string::npos || f.find("jpg") != std::string::npos;
  if (!png && !jpeg)
    throw InputError(context + ": compressed image format '" + c.format +
                     "' is not supported (expected jpeg or png)");
  const Image8 img = DecodeImage(c.data.data(), c.data.size(), context);
  // The bytes' own signature decides the extension (a "jpeg" message holding a PNG happens).
  const bool is_png = c.data.size() > 4 && c.data[0] == 0x89 && c.data[1] == 'P';
  return {c.data, is_png ? "png" : "jpg", img.width, img.height};
}

struct JointSample {
  std::int64_t stamp = 0;
  std::uint64_t order = 0;
  std::vector<double> q, tau;
};

struct FrameRef {
  std::int64_t stamp = 0;
  std::uint64_t message = 0;  // index among the image topic's messages
  Pose T_PC;
};

// An encoded frame waiting in the staging folder for its place in the session.
struct StagedFrame {
  std::string file, extension;
  int width = 0, height = 0;
};

// Workers that encode frames while the main thread reads the recording: a fixed pool (each
// keeps its encoder's scratch buffers warm), a bounded queue (the main thread waits when it is
// full), the first error rethrown by Drain().
class EncoderPool {
 public:
  using Job = std::function<void()>;
  explicit EncoderPool(unsigned threads) : capacity_(2 * threads) {
    for (unsigned i = 0; i < threads; ++i) workers_.emplace_back([this] { Work(); });
  }
  ~EncoderPool() {
    {
      std::lock_guard<std::mutex> lock(m_);
      stop_ = true;
    }
    ready_.notify_all();
    for (auto& w : workers_) w.join();
  }
  EncoderPool(const EncoderPool&) = delete;
  EncoderPool& operator=(const EncoderPool&) = delete;
  void Submit(Job job) {
    std::unique_lock<std::mutex> lock(m_);
    space_.wait(lock, [&] { return jobs_.size() < capacity_ || error_; });
    if (error_) std::rethrow_exception(error_);
    jobs_.push_back(std::move(job));
    ready_.notify_one();
  }
  void Drain() {
    std::unique_lock<std::mutex> lock(m_);
    space_.wait(lock, [&] { return (jobs_.empty() && busy_ == 0) || error_; });
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void Work() {
    std::unique_lock<std::mutex> lock(m_);
    while (true) {
      ready_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
      if (jobs_.empty()) return;  // stopping
      Job job = std::move(jobs_.front());
      jobs_.pop_front();
      ++busy_;
      space_.notify_all();
      lock.unlock();
      std::exception_ptr e;
      try {
        job();
      } catch (...) {
        e = std::current_exception();
      }
      lock.lock();
      --busy_;
      if (e && !error_) error_ = e;
      space_.notify_all();
    }
  }
  std::size_t capacity_;
  std::mutex m_;
  std::condition_variable ready_, space_;
  std::deque<Job> jobs_;
  int busy_ = 0;
  bool stop_ = false;
  std::exception_ptr error_;
  std::vector<std::thread> workers_;
};

// A folder beside the output for frames encoded while the recording is read; removed at the end.
class FrameStaging {
 public:
  explicit FrameStaging(const std::string& out)
      : dir_(PrepareStaging(fs::absolute(out).lexically_normal().string() + "-frames")) {
    std::error_code ec;
    fs::create_directories(dir_, ec);
    if (ec) throw InputError(dir_.string() + ": cannot create (" + ec.message() + ")");
  }
  ~FrameStaging() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  FrameStaging(const FrameStaging&) = delete;
  FrameStaging& operator=(const FrameStaging&) = delete;
  std::string File(std::uint64_t message, const std::string& extension) const {
    return (dir_ / ("message_" + std::to_string(message) + "." + extension)).string();
  }

 private:
  fs::path dir_;
};

std::string Seconds(double s) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(3) << s;
  return o.str();
}

}  // namespace

std::vector<std::string> ImportReport::Summary() const {
  std::vector<std::string> out;
  const double span = t_last - t_first;
  std::ostringstream j;
  j << "joints: " << samples << " samples from " << joints_topic << " (" << joint_messages
    << " messages), " << Seconds(span) << " s";
  if (span > 0 && samples > 1) j << " at " << std::setprecision(4) << (samples - 1) / span << " Hz";
  j << (torques ? ", with external torques" : ", no torques");
  out.push_back(j.str());
  if (out_of_order + duplicates + non_finite + outside_window > 0)
    out.push_back("  dropped: " + std::to_string(duplicates) + " duplicate stamps, " +
                  std::to_string(non_finite) + " with non-finite values, " +
                  std::to_string(outside_window) + " outside --start/--end; " +
                  std::to_string(out_of_order) + " out of order (sorted)");
  if (!image_topic.empty()) {
    out.push_back("images: " + std::to_string(frames) + " frames from " + image_topic + " (" +
                  std::to_string(image_messages) + " messages), camera " + camera_frame + " in " +
                  palm_frame + " from TF, intrinsics from " + camera_info_topic);
    if (frames_without_tf + frame_duplicates > 0)
      out.push_back("  dropped: " + std::to_string(frames_without_tf) +
                    " without TF at their stamp, " + std::to_string(frame_duplicates) +
                    " duplicate stamps");
  } else {
    out.push_back("images: none");
  }
  if (!object_pose_topic.empty())
    out.push_back("ground truth: " + std::to_string(truth_samples) + " poses from " +
                  object_pose_topic + " (" + std::to_string(truth_messages) + " messages, " +
                  std::to_string(truth_without_tf) + " without TF dropped)");
  out.push_back("time: t = 0 is stamp " + std::to_string(origin_ns / 1000000000) + "." + [&] {
    std::ostringstream o;
    o << std::setw(9) << std::setfill('0') << origin_ns % 1000000000;
    return o.str();
  }() + " s; " + format);
  return out;
}

std::string ListRecording(const std::string& path) {
  std::unique_ptr<Recording> rec = OpenRecording(path);
  const std::vector<TopicInfo> topics = rec->Topics();
  std::ostringstream out;
  out << rec->path() << ": " << rec->format() << ", " << topics.size() << " topics\n";
  std::size_t w = 5, wt = 4;
  for (const TopicInfo& t : topics)
    w = std::max(w, t.name.size()), wt = std::max(wt, t.type.size());
  out << std::left << std::setw(static_cast<int>(w) + 2) << "topic"
      << std::setw(static_cast<int>(wt) + 2) << "type" << std::right << std::setw(9) << "messages"
      << std::setw(11) << "rate [Hz]" << std::setw(11) << "span [s]"
      << "\n";
  std::vector<std::string> tf_topics;
  std::int64_t first = 0;
  for (const TopicInfo& t : topics)
    if (t.count > 0) first = first == 0 ? t.first_ns : std::min(first, t.first_ns);
  for (const TopicInfo& t : topics) {
    out << std::left << std::setw(static_cast<int>(w) + 2) << t.name
        << std::setw(static_cast<int>(wt) + 2) << t.type << std::right << std::setw(9) << t.count
        << std::setw(11) << std::fixed << std::setprecision(1) << t.Rate() << std::setw(11)
        << std::setprecision(3) << (t.count > 0 ? (t.last_ns - t.first_ns) * 1e-9 : 0.0) << "\n";
    if (MsgTypeOf(t.type) == MsgType::kTf) tf_topics.push_back(t.name);
  }
  TfTree tree;
  rec->Read(tf_topics, false, [&](Message& m) {
    const bool is_static = m.topic->find("static") != std::string::npos;
    for (const StampedTransform& t : std::get<TfMsg>(m.payload).transforms) tree.Add(t, is_static);
  });
  tree.Finish();
  const auto edges = tree.Edges();
  if (edges.empty()) {
    out << "TF: none (no /tf or /tf_static): the camera's pose cannot be imported from this "
           "recording\n";
  } else {
    out << "TF frames (frame <- parent):\n";
    for (const auto& [child, e] : edges)
      out << "  " << child << " <- " << e.parent
          << (e.is_static ? "  (static)" : "  (" + std::to_string(e.samples) + " transforms)")
          << "\n";
    if (tree.conflicts() > 0)
      out << "  (" << tree.conflicts() << " transforms gave a frame a second parent; ignored)\n";
  }
  return out.str();
}

ImportReport ImportRecording(const ImportOptions& opt,
                             const std::function<void(double)>& progress) {
  // Frames of about a megabyte are allocated and freed hundreds of times, across threads: glibc
  // would map and unmap each, and the page faults cost more than the PNG encoding. Keep them in
  // the heap (process-wide; it only delays returning memory to the kernel).
  mallopt(M_MMAP_THRESHOLD, 256 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  ImportReport report;
  // Inputs first, before reading anything big.
  if (opt.out.empty()) throw InputError("import: --out is required");
  if (fs::exists(fs::absolute(opt.out)) && !opt.overwrite)
    throw InputError(opt.out + ": already exists (pass --overwrite to replace it)");
  CheckOutputFolder(opt.out, {opt.recording, opt.hand_urdf, opt.object});
  if (!fs::is_regular_file(opt.object)) throw InputError(opt.object + ": object model not found");
  HandLoadOptions hand_options;
  hand_options.packages.dirs = opt.packages;
  hand_options.load_visual_meshes = false;
  const HandModel hand = LoadHandModel(opt.hand_urdf, hand_options);
  const std::vector<std::string> names = hand.QNames();
  if (names.empty()) throw InputError(opt.hand_urdf + ": the hand has no moving joints");
  for (const auto& [name, k] : opt.joint_stiffness) {
    if (name != "*" && std::find(names.begin(), names.end(), name) == names.end())
      throw InputError("import: --joint-stiffness: " + opt.hand_urdf +
                       " has no independent joint '" + name + "'");
    if (!(k > 0.0 && std::isfinite(k)))
      throw InputError("import: --joint-stiffness: " + name + " must be > 0 N m/rad");
  }

  std::unique_ptr<Recording> rec = OpenRecording(opt.recording);
  const std::string& path = rec->path();
  report.format = rec->format() + " " + path;
  const std::vector<TopicInfo> topics = rec->Topics();
  report.joints_topic = PickTopic(path, topics, opt.joints_topic, "--joints",
                                  {MsgType::kJointState}, "sensor_msgs/JointState", true);
  if (!opt.no_images)
    report.image_topic = PickTopic(path, topics, opt.image_topic, "--image",
                                   {MsgType::kImage, MsgType::kCompressedImage},
                                   "sensor_msgs/Image or sensor_msgs/CompressedImage", false);
  if (!report.image_topic.empty()) {
    std::string info = opt.camera_info_topic;
    if (info.empty()) {  // beside the image topic (/cam/image_raw → /cam/camera_info), else the
                         // only one
      const std::string ns = report.image_topic.substr(0, report.image_topic.rfind('/'));
      const TopicInfo* t = FindTopic(topics, ns + "/camera_info");
      if (t != nullptr && MsgTypeOf(t->type) == MsgType::kCameraInfo) info = t->name;
    }
    report.camera_info_topic = PickTopic(path, topics, info, "--camera-info",
                                         {MsgType::kCameraInfo}, "sensor_msgs/CameraInfo", true);
  }
  if (!opt.object_pose_topic.empty())
    report.object_pose_topic = PickTopic(
        path, topics, opt.object_pose_topic, "--object-pose",
        {MsgType::kPoseStamped, MsgType::kTransformStamped, MsgType::kOdometry},
        "geometry_msgs/PoseStamped, geometry_msgs/TransformStamped or nav_msgs/Odometry", true);
  report.palm_frame = opt.palm_frame.empty()
                          ? hand.links[static_cast<std::size_t>(hand.root_link)].name
                          : opt.palm_frame;
  report.torques = opt.effort_is_external;

  // Pass 1: everything but the images' pixels.
  std::vector<std::string> read;
  for (const std::string* t : {&report.joints_topic, &report.image_topic, &report.camera_info_topic,
                               &report.object_pose_topic})
    if (!t->empty()) read.push_back(*t);
  std::vector<std::string> tf_topics;
  for (const TopicInfo& t : topics)
    if (MsgTypeOf(t.type) == MsgType::kTf) tf_topics.push_back(t.name), read.push_back(t.name);

  std::vector<JointSample> joints;
  std::vector<int> column;  // per hand joint: its index in the current message's names
  std::vector<std::string> column_names;
  std::vector<std::pair<std::int64_t, std::uint64_t>> image_stamps;  // stamp, message index
  std::string image_frame;
  // Images are encoded on every core while the recording is read (one pass over it), into a
  // staging folder; which of them the session keeps is decided once TF is known.
  // Declared in this order so that the workers are joined (encoders destroyed) before the
  // slots they write and the folder they write into, also when an error unwinds the stack.
  std::optional<FrameStaging> staging;
  std::deque<StagedFrame> staged;  // by message index; elements stay put while it grows
  std::optional<EncoderPool> encoders;
  if (!report.image_topic.empty())
    staging.emplace(opt.out), encoders.emplace(std::max(1u, std::thread::hardware_concurrency()));
  std::optional<Intrinsics> K;
  std::vector<StampedTransform> truth;
  TfTree tree;
  rec->Read(
      read, true,
      [&](Message& m) {
        const std::string& topic = *m.topic;
        if (topic == report.joints_topic) {
          const auto& js = std::get<JointStateMsg>(m.payload);
          const std::string context =
              path + ": " + topic + " message " + std::to_string(report.joint_messages);
          ++report.joint_messages;
          if (js.name != column_names) {  // the mapping by name, redone when the names change
            column_names = js.name;
            column.assign(names.size(), -1);
            std::vector<std::string> missing;
            for (std::size_t j = 0; j < names.size(); ++j) {
              const auto it = std::find(js.name.begin(), js.name.end(), names[j]);
              if (it == js.name.end())
                missing.push_back(names[j]);
              else
                column[j] = static_cast<int>(it - js.name.begin());
            }
            if (!missing.empty())
              throw InputError(context + ": the hand's joint" + (missing.size() > 1 ? "s " : " ") +
                               Join(missing, 6) + (missing.size() > 1 ? " are" : " is") +
                               " not in the message, which names " + Join(js.name) + " (" +
                               opt.hand_urdf + " names " + Join(names) + ")");
          }
          if (js.position.size() != js.name.size())
            throw InputError(context + ": " + std::to_string(js.name.size()) + " names but " +
                             std::to_string(js.position.size()) + " positions");
          if (opt.effort_is_external && js.effort.size() != js.name.size())
            throw InputError(context + ": --effort-is external, but the message has " +
                             std::to_string(js.effort.size()) + " efforts for " +
                             std::to_string(js.name.size()) + " joints");
          JointSample s;
          s.stamp = StampOf(js.header, m.log_ns);
          s.order = report.joint_messages;
          s.q.resize(names.size());
          bool finite = true;
          for (std::size_t j = 0; j < names.size(); ++j)
            finite &= std::isfinite(s.q[j] = js.position[static_cast<std::size_t>(column[j])]);
          if (opt.effort_is_external) {
            s.tau.resize(names.size());
            for (std::size_t j = 0; j < names.size(); ++j)
              finite &= std::isfinite(s.tau[j] = js.effort[static_cast<std::size_t>(column[j])]);
          }
          if (!finite) {
            ++report.non_finite;
            return;
          }
          joints.push_back(std::move(s));
        } else if (topic == report.image_topic) {
          const Header& h = std::holds_alternative<ImageMsg>(m.payload)
                                ? std::get<ImageMsg>(m.payload).header
                                : std::get<CompressedImageMsg>(m.payload).header;
          if (image_frame.empty()) image_frame = h.frame_id;
          const std::uint64_t index = report.image_messages++;
          image_stamps.emplace_back(StampOf(h, m.log_ns), index);
          StagedFrame* slot = &staged.emplace_back();
          auto payload = std::make_shared<Payload>(std::move(m.payload));
          const std::string context = path + ": " + topic + " message " + std::to_string(index);
          encoders->Submit([payload, context, index, slot, &staging]() mutable {
            Encoded e = EncodeFrame(*payload, context);
            payload.reset();  // the pixels go as soon as they are encoded
            const std::string file = staging->File(index, e.extension);
            std::ofstream out(file, std::ios::binary);
            out.write(reinterpret_cast<const char*>(e.bytes.data()),
                      static_cast<std::streamsize>(e.bytes.size()));
            out.close();
            if (!out) throw InputError(file + ": cannot write");
            *slot = StagedFrame{file, e.extension, e.width, e.height};
          });
        } else if (topic == report.camera_info_topic) {
          if (!K) {
            K = IntrinsicsOf(std::get<CameraInfoMsg>(m.payload),
                             path + ": " + topic + " message 0");
          }
        } else if (topic == report.object_pose_topic) {
          StampedTransform t = std::get<StampedTransform>(m.payload);
          t.header.stamp_ns = StampOf(t.header, m.log_ns);
          if (t.header.frame_id.empty())
            throw InputError(path + ": " + topic + " message " +
                             std::to_string(report.truth_messages) +
                             " has no frame_id: in which frame is the object's pose?");
          truth.push_back(t);
          ++report.truth_messages;
        }
        if (std::find(tf_topics.begin(), tf_topics.end(), topic) != tf_topics.end()) {
          const bool is_static = topic.find("static") != std::string::npos;
          for (const StampedTransform& t : std::get<TfMsg>(m.payload).transforms)
            tree.Add(t, is_static);
        }
      },
      progress);
  if (encoders) encoders->Drain();
  tree.Finish();

  // Joint samples in stamp order (stable: equal stamps keep file order), duplicates dropped.
  if (joints.empty())
    throw InputError(path + ": " + report.joints_topic + " has no usable joint samples");
  for (std::size_t i = 1; i < joints.size(); ++i)
    report.out_of_order += joints[i].stamp < joints[i - 1].stamp;
  std::stable_sort(joints.begin(), joints.end(),
                   [](const JointSample& a, const JointSample& b) { return a.stamp < b.stamp; });
  {
    std::vector<JointSample> unique;
    unique.reserve(joints.size());
    for (JointSample& s : joints) {
      if (!unique.empty() && unique.back().stamp == s.stamp) {
        ++report.duplicates;
        continue;
      }
      unique.push_back(std::move(s));
    }
    joints.swap(unique);
  }
  const std::int64_t first_ns = joints.front().stamp;
  const auto ns_of = [](double s) { return static_cast<std::int64_t>(std::llround(s * 1e9)); };
  const std::int64_t lo =
      opt.start_s ? first_ns + ns_of(*opt.start_s) : std::numeric_limits<std::int64_t>::min();
  const std::int64_t hi =
      opt.end_s ? first_ns + ns_of(*opt.end_s) : std::numeric_limits<std::int64_t>::max();
  if (opt.start_s && opt.end_s && *opt.end_s <= *opt.start_s)
    throw InputError("import: --end must be after --start");
  {
    const std::size_t before = joints.size();
    joints.erase(std::remove_if(joints.begin(), joints.end(),
                                [&](const JointSample& s) { return s.stamp < lo || s.stamp > hi; }),
                 joints.end());
    report.outside_window = before - joints.size();
  }
  if (joints.empty()) throw InputError(path + ": no joint samples between --start and --end");
  report.origin_ns = opt.time_origin_s ? ns_of(*opt.time_origin_s) : joints.front().stamp;
  // t in seconds from the origin: the integer nanoseconds divided once (correctly rounded).
  const auto t_of = [&](std::int64_t stamp) {
    return static_cast<double>(stamp - report.origin_ns) / 1e9;
  };
  report.samples = joints.size();
  report.t_first = t_of(joints.front().stamp);
  report.t_last = t_of(joints.back().stamp);

  // The camera's pose at each frame, from TF.
  std::vector<FrameRef> frames;
  if (!report.image_topic.empty()) {
    if (!K)
      throw InputError(path + ": " + report.camera_info_topic +
                       " has no messages: the camera's intrinsics are unknown");
    report.camera_frame = opt.camera_frame.empty() ? image_frame : opt.camera_frame;
    if (report.camera_frame.empty())
      throw InputError(
          path + ": " + report.image_topic +
          " messages have no frame_id; name the camera's TF frame with --camera-frame");
    try {
      tree.RequireConnected(report.palm_frame, report.camera_frame);
    } catch (const InputError& e) {
      throw InputError(path + ": " + e.what());
    }
    std::stable_sort(image_stamps.begin(), image_stamps.end());
    for (const auto& [stamp, index] : image_stamps) {
      if (stamp < lo || stamp > hi) continue;
      if (!frames.empty() && frames.back().stamp == stamp) {
        ++report.frame_duplicates;
        continue;
      }
      const StagedFrame& f = staged[index];
      if (f.width != K->width || f.height != K->height)
        throw InputError(path + ": " + report.image_topic + " message " + std::to_string(index) +
                         ": image is " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                         ", camera_info says " + std::to_string(K->width) + "x" +
                         std::to_string(K->height));
      const auto T =
          tree.Lookup(report.palm_frame, report.camera_frame, stamp, true, ns_of(opt.max_tf_gap_s));
      if (!T) {
        ++report.frames_without_tf;
        continue;
      }
      frames.push_back({stamp, index, *T});
    }
  }

  // Ground truth in the palm frame.
  std::vector<std::pair<std::int64_t, Pose>> gt;
  for (const StampedTransform& t : truth) {
    if (t.header.stamp_ns < lo || t.header.stamp_ns > hi) continue;
    if (t.header.frame_id != report.palm_frame) {
      try {
        tree.RequireConnected(report.palm_frame, t.header.frame_id);
      } catch (const InputError& e) {
        throw InputError(path + ": " + report.object_pose_topic + ": " + e.what());
      }
    }
    if (t.header.frame_id == report.palm_frame) {  // as recorded, digit for digit
      gt.emplace_back(t.header.stamp_ns, t.T);
      continue;
    }
    const auto T = tree.Lookup(report.palm_frame, t.header.frame_id, t.header.stamp_ns, true,
                               ns_of(opt.max_tf_gap_s));
    if (!T) {
      ++report.truth_without_tf;
      continue;
    }
    gt.emplace_back(t.header.stamp_ns, *T * t.T);
  }
  std::stable_sort(gt.begin(), gt.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  gt.erase(std::unique(gt.begin(), gt.end(),
                       [](const auto& a, const auto& b) { return a.first == b.first; }),
           gt.end());
  report.truth_samples = gt.size();

  SessionInfo info;
  info.name = fs::path(opt.recording).stem().string();
  info.hand_urdf = fs::absolute(opt.hand_urdf).lexically_normal().string();
  for (const auto& [name, dir] : opt.packages)
    info.packages[name] = fs::absolute(dir).lexically_normal().string();
  info.object = fs::absolute(opt.object).lexically_normal().string();
  if (!frames.empty()) info.camera = K;
  info.joint_stiffness = opt.joint_stiffness;
  if (opt.initial_pose)
    info.initial_T_PO = *opt.initial_pose;
  else if (!gt.empty())
    info.initial_T_PO = gt.front().second.ToTransform();
  else
    throw InputError(path +
                     ": no initial estimate of the object's pose: pass --initial-pose "
                     "x,y,z,qw,qx,qy,qz (palm frame) or a ground-truth topic with --object-pose");
  if (opt.initial_sigma) {
    info.sigma_position = (*opt.initial_sigma)[0];
    info.sigma_orientation = (*opt.initial_sigma)[1];
    info.sigma_joint_bias = (*opt.initial_sigma)[2];
    if (!(info.sigma_position >= 1e-6 && info.sigma_position <= 10 &&
          info.sigma_orientation >= 1e-6 && info.sigma_orientation <= 2 * M_PI &&
          info.sigma_joint_bias >= 0 && info.sigma_joint_bias <= 2 * M_PI))
      throw InputError(
          "import: --initial-sigma: expected position in [1e-6, 10] m, orientation in [1e-6, 2 pi] "
          "rad, bias in [0, 2 pi] rad");
  }
  {
    std::ostringstream prov;
    prov << "{\"importer\": \"inhand import\", \"recording\": \""
         << fs::absolute(opt.recording).lexically_normal().string() << "\", \"format\": \""
         << rec->format() << "\", \"joints_topic\": \"" << report.joints_topic
         << "\", \"image_topic\": \"" << report.image_topic << "\", \"object_pose_topic\": \""
         << report.object_pose_topic << "\", \"palm_frame\": \"" << report.palm_frame
         << "\", \"camera_frame\": \"" << report.camera_frame
         << "\", \"time_origin_ns\": " << report.origin_ns
         << ", \"torques\": " << (report.torques ? "\"external\"" : "null") << "}";
    info.provenance_json = prov.str();
  }

  SessionWriter writer(opt.out, info, names, opt.overwrite, report.torques);
  for (const JointSample& s : joints)
    writer.AddJointSample(
        t_of(s.stamp), Eigen::Map<const Eigen::VectorXd>(s.q.data(), static_cast<long>(s.q.size())),
        Eigen::Map<const Eigen::VectorXd>(s.tau.data(), static_cast<long>(s.tau.size())));
  for (const auto& [stamp, T] : gt) writer.AddGroundTruth(t_of(stamp), T.p, T.q);

  // The frames kept, in stamp order, moved from the staging folder.
  for (const FrameRef& f : frames) {
    const StagedFrame& sf = staged[f.message];
    writer.AdoptCameraFrame(t_of(f.stamp), sf.file, sf.extension, f.T_PC.p, f.T_PC.q);
  }
  report.frames = frames.size();
  writer.Commit();
  return report;
}

}  // namespace inhand::ros
