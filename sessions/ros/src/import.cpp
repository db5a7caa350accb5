#include "inhand/ros/import.hpp"

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

#include "frame_staging.hpp"
#include "inhand/core/error.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/ros/camera_messages.hpp"
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

// One import, in its steps: scan (the options, the hand, the topics), decode (the recording read
// once: joint samples, camera frames encoded on every core into a staging folder, intrinsics,
// ground truth, TF), align (the samples ordered and windowed, the frames placed by TF, the truth
// moved into the palm frame), write (the session).
class Importer {
 public:
  Importer(const ImportOptions& opt, const std::function<void(double)>& progress)
      : opt_(opt), progress_(progress) {}
  ImportReport Run();

 private:
  void CheckOptions();
  void ScanTopics();
  void Decode();
  void OnJointState(const Message& m);
  void OnImage(Message& m);
  void OnObjectPose(const Message& m);
  void OrderJointSamples();
  void PlaceFrames();
  void TruthInPalmFrame();
  SessionInfo Info() const;
  void Write(const SessionInfo& info);
  std::int64_t Nanoseconds(double s) const { return std::llround(s * 1e9); }
  // t in seconds from the origin: the integer nanoseconds divided once (correctly rounded).
  double T(std::int64_t stamp) const {
    return static_cast<double>(stamp - report_.origin_ns) / 1e9;
  }

  const ImportOptions& opt_;
  const std::function<void(double)>& progress_;
  ImportReport report_;
  HandModel hand_;
  std::vector<std::string> names_;  // the hand's independent joints
  std::unique_ptr<Recording> rec_;
  std::string path_;
  std::vector<TopicInfo> topics_;
  std::vector<std::string> tf_topics_;
  // Decoded.
  std::vector<JointSample> joints_;
  std::vector<int> column_;  // per hand joint: its index in the current message's names
  std::vector<std::string> column_names_;
  std::vector<std::pair<std::int64_t, std::uint64_t>> image_stamps_;  // stamp, message index
  std::string image_frame_;
  // Images are encoded on every core while the recording is read (one pass over it), into a
  // staging folder; which of them the session keeps is decided once TF is known. Declared in this
  // order so that the workers are joined (encoders destroyed) before the slots they write and the
  // folder they write into, also when an error unwinds the stack.
  std::optional<FrameStaging> staging_;
  std::deque<StagedFrame> staged_;  // by message index; elements stay put while it grows
  std::optional<EncoderPool> encoders_;
  std::optional<Intrinsics> K_;
  std::vector<StampedTransform> truth_;
  TfTree tree_;
  // Aligned.
  std::int64_t lo_ = std::numeric_limits<std::int64_t>::min();  // the --start/--end window
  std::int64_t hi_ = std::numeric_limits<std::int64_t>::max();
  std::vector<FrameRef> frames_;
  std::vector<std::pair<std::int64_t, Pose>> gt_;
};

ImportReport Importer::Run() {
  CheckOptions();
  ScanTopics();
  Decode();
  OrderJointSamples();
  PlaceFrames();
  TruthInPalmFrame();
  Write(Info());
  return report_;
}

// The options and the hand, before reading anything big.
void Importer::CheckOptions() {
  if (opt_.out.empty()) throw InputError("import: --out is required");
  if (fs::exists(fs::absolute(opt_.out)) && !opt_.overwrite)
    throw InputError(opt_.out + ": already exists (pass --overwrite to replace it)");
  CheckOutputFolder(opt_.out, {opt_.recording, opt_.hand_urdf, opt_.object});
  if (!fs::is_regular_file(opt_.object)) throw InputError(opt_.object + ": object model not found");
  HandLoadOptions hand_options;
  hand_options.packages.dirs = opt_.packages;
  hand_options.load_visual_meshes = false;
  hand_ = LoadHandModel(opt_.hand_urdf, hand_options);
  names_ = hand_.QNames();
  if (names_.empty()) throw InputError(opt_.hand_urdf + ": the hand has no moving joints");
  for (const auto& [name, k] : opt_.joint_stiffness) {
    if (name != "*" && std::find(names_.begin(), names_.end(), name) == names_.end())
      throw InputError("import: --joint-stiffness: " + opt_.hand_urdf +
                       " has no independent joint '" + name + "'");
    if (!(k > 0.0 && std::isfinite(k)))
      throw InputError("import: --joint-stiffness: " + name + " must be > 0 N m/rad");
  }
  if (opt_.start_s && opt_.end_s && *opt_.end_s <= *opt_.start_s)
    throw InputError("import: --end must be after --start");
}

// The recording's topics, and those the import reads.
void Importer::ScanTopics() {
  rec_ = OpenRecording(opt_.recording);
  path_ = rec_->path();
  report_.format = rec_->format() + " " + path_;
  topics_ = rec_->Topics();
  report_.joints_topic = PickTopic(path_, topics_, opt_.joints_topic, "--joints",
                                   {MsgType::kJointState}, "sensor_msgs/JointState", true);
  if (!opt_.no_images)
    report_.image_topic = PickTopic(path_, topics_, opt_.image_topic, "--image",
                                    {MsgType::kImage, MsgType::kCompressedImage},
                                    "sensor_msgs/Image or sensor_msgs/CompressedImage", false);
  if (!report_.image_topic.empty()) {
    std::string info = opt_.camera_info_topic;
    if (info.empty()) {  // beside the image topic (/cam/image_raw → /cam/camera_info)
      const std::string ns = report_.image_topic.substr(0, report_.image_topic.rfind('/'));
      const TopicInfo* t = FindTopic(topics_, ns + "/camera_info");
      if (t != nullptr && MsgTypeOf(t->type) == MsgType::kCameraInfo) info = t->name;
    }
    report_.camera_info_topic = PickTopic(path_, topics_, info, "--camera-info",
                                          {MsgType::kCameraInfo}, "sensor_msgs/CameraInfo", true);
  }
  if (!opt_.object_pose_topic.empty())
    report_.object_pose_topic = PickTopic(
        path_, topics_, opt_.object_pose_topic, "--object-pose",
        {MsgType::kPoseStamped, MsgType::kTransformStamped, MsgType::kOdometry},
        "geometry_msgs/PoseStamped, geometry_msgs/TransformStamped or nav_msgs/Odometry", true);
  report_.palm_frame = opt_.palm_frame.empty()
                           ? hand_.links[static_cast<std::size_t>(hand_.root_link)].name
                           : opt_.palm_frame;
  report_.torques = opt_.effort_is_external;
  for (const TopicInfo& t : topics_)
    if (MsgTypeOf(t.type) == MsgType::kTf) tf_topics_.push_back(t.name);
}

// One pass over the recording: everything but the images' pixels kept, the pixels encoded.
void Importer::Decode() {
  std::vector<std::string> read;
  for (const std::string* t : {&report_.joints_topic, &report_.image_topic,
                               &report_.camera_info_topic, &report_.object_pose_topic})
    if (!t->empty()) read.push_back(*t);
  for (const std::string& t : tf_topics_) read.push_back(t);
  if (!report_.image_topic.empty())
    staging_.emplace(opt_.out),
        encoders_.emplace(std::max(1u, std::thread::hardware_concurrency()));
  rec_->Read(
      read, true,
      [&](Message& m) {
        const std::string& topic = *m.topic;
        if (topic == report_.joints_topic) {
          OnJointState(m);
        } else if (topic == report_.image_topic) {
          OnImage(m);
        } else if (topic == report_.camera_info_topic) {
          if (!K_)
            K_ = IntrinsicsOf(std::get<CameraInfoMsg>(m.payload),
                              path_ + ": " + topic + " message 0");
        } else if (topic == report_.object_pose_topic) {
          OnObjectPose(m);
        }
        if (std::find(tf_topics_.begin(), tf_topics_.end(), topic) != tf_topics_.end()) {
          const bool is_static = topic.find("static") != std::string::npos;
          for (const StampedTransform& t : std::get<TfMsg>(m.payload).transforms)
            tree_.Add(t, is_static);
        }
      },
      progress_);
  if (encoders_) encoders_->Drain();
  tree_.Finish();
}

// The hand's joints picked from the message by name (the mapping redone when the names change);
// a sample with a value that is not a number is dropped (counted).
void Importer::OnJointState(const Message& m) {
  const auto& js = std::get<JointStateMsg>(m.payload);
  const std::string context =
      path_ + ": " + *m.topic + " message " + std::to_string(report_.joint_messages);
  ++report_.joint_messages;
  if (js.name != column_names_) {
    column_names_ = js.name;
    std::vector<std::string> missing;
    column_ = ColumnsByName(names_, js.name, missing);
    if (!missing.empty())
      throw InputError(context + ": the hand's joint" + (missing.size() > 1 ? "s " : " ") +
                       Join(missing, 6) + (missing.size() > 1 ? " are" : " is") +
                       " not in the message, which names " + Join(js.name) + " (" + opt_.hand_urdf +
                       " names " + Join(names_) + ")");
  }
  if (js.position.size() != js.name.size())
    throw InputError(context + ": " + std::to_string(js.name.size()) + " names but " +
                     std::to_string(js.position.size()) + " positions");
  if (opt_.effort_is_external && js.effort.size() != js.name.size())
    throw InputError(context + ": --effort-is external, but the message has " +
                     std::to_string(js.effort.size()) + " efforts for " +
                     std::to_string(js.name.size()) + " joints");
  JointSample s;
  s.stamp = StampOf(js.header, m.log_ns);
  s.order = report_.joint_messages;
  s.q.resize(names_.size());
  bool finite = true;
  for (std::size_t j = 0; j < names_.size(); ++j)
    finite &= std::isfinite(s.q[j] = js.position[static_cast<std::size_t>(column_[j])]);
  if (opt_.effort_is_external) {
    s.tau.resize(names_.size());
    for (std::size_t j = 0; j < names_.size(); ++j)
      finite &= std::isfinite(s.tau[j] = js.effort[static_cast<std::size_t>(column_[j])]);
  }
  if (!finite) {
    ++report_.non_finite;
    return;
  }
  joints_.push_back(std::move(s));
}

// The image's stamp kept; its pixels handed to an encoder, which writes the frame's file into
// the staging folder and fills its slot.
void Importer::OnImage(Message& m) {
  const Header& h = std::holds_alternative<ImageMsg>(m.payload)
                        ? std::get<ImageMsg>(m.payload).header
                        : std::get<CompressedImageMsg>(m.payload).header;
  if (image_frame_.empty()) image_frame_ = h.frame_id;
  const std::uint64_t index = report_.image_messages++;
  image_stamps_.emplace_back(StampOf(h, m.log_ns), index);
  StagedFrame* slot = &staged_.emplace_back();
  auto payload = std::make_shared<Payload>(std::move(m.payload));
  const std::string context = path_ + ": " + *m.topic + " message " + std::to_string(index);
  const FrameStaging* staging = &*staging_;
  encoders_->Submit([payload, context, index, slot, staging]() mutable {
    const Encoded e = EncodeFrame(*payload, context);
    payload.reset();  // the pixels go as soon as they are encoded
    *slot = staging->Stage(index, e);
  });
}

void Importer::OnObjectPose(const Message& m) {
  StampedTransform t = std::get<StampedTransform>(m.payload);
  t.header.stamp_ns = StampOf(t.header, m.log_ns);
  if (t.header.frame_id.empty())
    throw InputError(path_ + ": " + *m.topic + " message " +
                     std::to_string(report_.truth_messages) +
                     " has no frame_id: in which frame is the object's pose?");
  truth_.push_back(t);
  ++report_.truth_messages;
}

// Joint samples in stamp order (stable: equal stamps keep file order), duplicates dropped, those
// outside --start/--end dropped; the time origin.
void Importer::OrderJointSamples() {
  if (joints_.empty())
    throw InputError(path_ + ": " + report_.joints_topic + " has no usable joint samples");
  for (std::size_t i = 1; i < joints_.size(); ++i)
    report_.out_of_order += joints_[i].stamp < joints_[i - 1].stamp;
  std::stable_sort(joints_.begin(), joints_.end(),
                   [](const JointSample& a, const JointSample& b) { return a.stamp < b.stamp; });
  std::vector<JointSample> unique;
  unique.reserve(joints_.size());
  for (JointSample& s : joints_) {
    if (!unique.empty() && unique.back().stamp == s.stamp) {
      ++report_.duplicates;
      continue;
    }
    unique.push_back(std::move(s));
  }
  joints_.swap(unique);
  const std::int64_t first_ns = joints_.front().stamp;
  if (opt_.start_s) lo_ = first_ns + Nanoseconds(*opt_.start_s);
  if (opt_.end_s) hi_ = first_ns + Nanoseconds(*opt_.end_s);
  const std::size_t before = joints_.size();
  joints_.erase(
      std::remove_if(joints_.begin(), joints_.end(),
                     [&](const JointSample& s) { return s.stamp < lo_ || s.stamp > hi_; }),
      joints_.end());
  report_.outside_window = before - joints_.size();
  if (joints_.empty()) throw InputError(path_ + ": no joint samples between --start and --end");
  report_.origin_ns = opt_.time_origin_s ? Nanoseconds(*opt_.time_origin_s) : joints_.front().stamp;
  report_.samples = joints_.size();
  report_.t_first = T(joints_.front().stamp);
  report_.t_last = T(joints_.back().stamp);
}

// The camera's pose in the palm frame at each frame's stamp, from TF; frames without it dropped.
void Importer::PlaceFrames() {
  if (report_.image_topic.empty()) return;
  if (!K_)
    throw InputError(path_ + ": " + report_.camera_info_topic +
                     " has no messages: the camera's intrinsics are unknown");
  report_.camera_frame = opt_.camera_frame.empty() ? image_frame_ : opt_.camera_frame;
  if (report_.camera_frame.empty())
    throw InputError(path_ + ": " + report_.image_topic +
                     " messages have no frame_id; name the camera's TF frame with --camera-frame");
  try {
    tree_.RequireConnected(report_.palm_frame, report_.camera_frame);
  } catch (const InputError& e) {
    throw InputError(path_ + ": " + e.what());
  }
  std::stable_sort(image_stamps_.begin(), image_stamps_.end());
  for (const auto& [stamp, index] : image_stamps_) {
    if (stamp < lo_ || stamp > hi_) continue;
    if (!frames_.empty() && frames_.back().stamp == stamp) {
      ++report_.frame_duplicates;
      continue;
    }
    const StagedFrame& f = staged_[index];
    if (f.width != K_->width || f.height != K_->height)
      throw InputError(path_ + ": " + report_.image_topic + " message " + std::to_string(index) +
                       ": image is " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                       ", camera_info says " + std::to_string(K_->width) + "x" +
                       std::to_string(K_->height));
    const auto T_PC = tree_.Lookup(report_.palm_frame, report_.camera_frame, stamp, true,
                                   Nanoseconds(opt_.max_tf_gap_s));
    if (!T_PC) {
      ++report_.frames_without_tf;
      continue;
    }
    frames_.push_back({stamp, index, *T_PC});
  }
  report_.frames = frames_.size();
}

// Ground truth in the palm frame: as recorded when it is given there, else through TF.
void Importer::TruthInPalmFrame() {
  for (const StampedTransform& t : truth_) {
    if (t.header.stamp_ns < lo_ || t.header.stamp_ns > hi_) continue;
    if (t.header.frame_id == report_.palm_frame) {  // as recorded, digit for digit
      gt_.emplace_back(t.header.stamp_ns, t.T);
      continue;
    }
    try {
      tree_.RequireConnected(report_.palm_frame, t.header.frame_id);
    } catch (const InputError& e) {
      throw InputError(path_ + ": " + report_.object_pose_topic + ": " + e.what());
    }
    const auto T = tree_.Lookup(report_.palm_frame, t.header.frame_id, t.header.stamp_ns, true,
                                Nanoseconds(opt_.max_tf_gap_s));
    if (!T) {
      ++report_.truth_without_tf;
      continue;
    }
    gt_.emplace_back(t.header.stamp_ns, *T * t.T);
  }
  std::stable_sort(gt_.begin(), gt_.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  gt_.erase(std::unique(gt_.begin(), gt_.end(),
                        [](const auto& a, const auto& b) { return a.first == b.first; }),
            gt_.end());
  report_.truth_samples = gt_.size();
}

// What the session says about itself: models, camera, initial estimate and its σ, provenance.
SessionInfo Importer::Info() const {
  SessionInfo info;
  info.name = fs::path(opt_.recording).stem().string();
  info.hand_urdf = fs::absolute(opt_.hand_urdf).lexically_normal().string();
  for (const auto& [name, dir] : opt_.packages)
    info.packages[name] = fs::absolute(dir).lexically_normal().string();
  info.object = fs::absolute(opt_.object).lexically_normal().string();
  if (!frames_.empty()) info.camera = K_;
  info.joint_stiffness = opt_.joint_stiffness;
  if (opt_.initial_pose)
    info.initial_T_PO = *opt_.initial_pose;
  else if (!gt_.empty())
    info.initial_T_PO = gt_.front().second.ToTransform();
  else
    throw InputError(path_ +
                     ": no initial estimate of the object's pose: pass --initial-pose "
                     "x,y,z,qw,qx,qy,qz (palm frame) or a ground-truth topic with --object-pose");
  if (opt_.initial_sigma) {
    info.sigma_position = (*opt_.initial_sigma)[0];
    info.sigma_orientation = (*opt_.initial_sigma)[1];
    info.sigma_joint_bias = (*opt_.initial_sigma)[2];
    if (!(info.sigma_position >= 1e-6 && info.sigma_position <= 10 &&
          info.sigma_orientation >= 1e-6 && info.sigma_orientation <= 2 * M_PI &&
          info.sigma_joint_bias >= 0 && info.sigma_joint_bias <= 2 * M_PI))
      throw InputError(
          "import: --initial-sigma: expected position in [1e-6, 10] m, orientation in [1e-6, 2 pi] "
          "rad, bias in [0, 2 pi] rad");
  }
  const jsonf::Json provenance = {
      {"importer", "inhand import"},
      {"recording", fs::absolute(opt_.recording).lexically_normal().string()},
      {"format", rec_->format()},
      {"joints_topic", report_.joints_topic},
      {"image_topic", report_.image_topic},
      {"object_pose_topic", report_.object_pose_topic},
      {"palm_frame", report_.palm_frame},
      {"camera_frame", report_.camera_frame},
      {"time_origin_ns", report_.origin_ns},
      {"torques", report_.torques ? jsonf::Json("external") : jsonf::Json(nullptr)}};
  info.provenance_json = provenance.dump();
  return info;
}

// The session: joint samples, ground truth, and the frames kept, in stamp order, moved from the
// staging folder.
void Importer::Write(const SessionInfo& info) {
  SessionWriter writer(opt_.out, info, names_, opt_.overwrite, report_.torques);
  for (const JointSample& s : joints_)
    writer.AddJointSample(
        T(s.stamp), Eigen::Map<const Eigen::VectorXd>(s.q.data(), static_cast<long>(s.q.size())),
        Eigen::Map<const Eigen::VectorXd>(s.tau.data(), static_cast<long>(s.tau.size())));
  for (const auto& [stamp, T_PO] : gt_) writer.AddGroundTruth(T(stamp), T_PO.p, T_PO.q);
  for (const FrameRef& f : frames_) {
    const StagedFrame& sf = staged_[f.message];
    writer.AdoptCameraFrame(T(f.stamp), sf.file, sf.extension, f.T_PC.p, f.T_PC.q);
  }
  writer.Commit();
}

}  // namespace

ImportReport ImportRecording(const ImportOptions& opt,
                             const std::function<void(double)>& progress) {
  return Importer(opt, progress).Run();
}

}  // namespace inhand::ros
