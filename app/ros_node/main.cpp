// inhand_ros_node: the estimator live on a ROS 1 robot. Subscribes the hand's JointState, a
// camera (Image or CompressedImage, with CameraInfo) and TF; publishes per modality set the
// object's PoseWithCovarianceStamped, TF palm → object_<set>, the health (latched) and the
// tracker's events; optionally the annotated camera image (Fig. 1) at a reduced rate. Options from
// flags, else from the node's private parameters (~name, the flag's name with '_' for '-'); README
// "A live ROS 1 node".
#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <type_traits>

#include "annotator.hpp"
#include "inhand/app/evaluation.hpp"
#include "inhand/core/error.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/ros/camera_messages.hpp"
#include "inhand/tracker/tracker_params.hpp"
#include "live_tracking.hpp"

namespace inhand::ros {
namespace {

using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;

Header HeaderOf(const std_msgs::Header& h) {
  // A stamp of 0 is unset: the time of arrival stands for it.
  const ::ros::Time stamp = h.stamp.isZero() ? ::ros::Time::now() : h.stamp;
  return {static_cast<std::int64_t>(stamp.toNSec()), h.frame_id};
}

::ros::Time StampOf(std::int64_t ns) {
  ::ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(ns));
  return t;
}

// Everything the node is told, before it is checked.
struct NodeOptions {
  std::string hand, object, params_file, params_json,
      sets = "jt", joint_states = "/joint_states", image, compressed_image, camera_info,
      effort_is = "none", palm_frame, camera_frame, start, start_frame, start_sigma,
      object_frame_prefix = "object_", stats_out;
  std::vector<std::string> packages;
  double time_origin = -1.0, horizon = 0.5, annotated_rate = 0.0;
  bool deterministic = false;
};

std::vector<double> Numbers(const std::string& text, const std::string& flag, std::size_t n) {
  std::string s = text;
  std::replace(s.begin(), s.end(), ',', ' ');
  std::istringstream in(s);
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  if (!in.eof() || v.size() != n ||
      !std::all_of(v.begin(), v.end(), [](double d) { return std::isfinite(d); }))
    throw InputError(flag + ": '" + text + "', expected " + std::to_string(n) +
                     " finite numbers separated by spaces or commas");
  return v;
}

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> out;
  std::string s = text;
  std::replace(s.begin(), s.end(), ',', ' ');
  std::istringstream in(s);
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

LiveOptions LiveOptionsOf(const NodeOptions& o) {
  LiveOptions l;
  l.sets = Split(o.sets);
  if (!o.params_file.empty() && !o.params_json.empty())
    throw InputError("--params and --params-json: give one of them");
  if (!o.params_file.empty()) l.params = ReadTrackerParams(o.params_file);
  if (!o.params_json.empty()) l.params = TrackerParamsFromJson(o.params_json, "--params-json");
  l.threaded = !o.deterministic;
  if (o.effort_is != "external" && o.effort_is != "none")
    throw InputError("--effort-is: '" + o.effort_is + "', expected external or none");
  l.effort_is_external = o.effort_is == "external";
  l.palm_frame = o.palm_frame;
  l.camera_frame = o.camera_frame;
  if (!o.start.empty() && !o.start_frame.empty())
    throw InputError("--start and --start-frame: give one of them");
  if (!o.start.empty()) {
    // x y z qw qx qy qz: the object's pose in the palm frame [m], a unit quaternion.
    const std::vector<double> v = Numbers(o.start, "--start", 7);
    l.start_T_PO =
        MakeTransform(Vec3(v[0], v[1], v[2]), MessageQuaternion(v[3], v[4], v[5], v[6], "--start"));
  }
  l.start_frame = o.start_frame;
  if (!o.start_sigma.empty()) {
    const std::vector<double> v = Numbers(o.start_sigma, "--start-sigma", 3);
    l.start_sigmas.position = v[0];
    l.start_sigmas.orientation = v[1];
    l.start_sigmas.bias = v[2];
  }
  if (o.time_origin >= 0.0) l.time_origin_ns = std::llround(o.time_origin * 1e9);
  if (!(o.horizon > 0.0 && o.horizon <= 10.0))
    throw InputError("--horizon: " + std::to_string(o.horizon) + ", expected (0, 10] s");
  l.horizon = o.horizon;
  return l;
}

std::string CameraInfoTopic(const NodeOptions& o) {
  if (!o.camera_info.empty()) return o.camera_info;
  // Beside the image, as image_transport names it: /ns/image_raw[/compressed] → /ns/camera_info.
  std::string image = !o.image.empty() ? o.image : o.compressed_image;
  if (!o.compressed_image.empty() && image.size() > 11 &&
      image.compare(image.size() - 11, 11, "/compressed") == 0)
    image.resize(image.size() - 11);
  const std::size_t slash = image.rfind('/');
  return (slash == std::string::npos ? std::string() : image.substr(0, slash)) + "/camera_info";
}

class Node {
 public:
  Node(const NodeOptions& o, const HandModel& hand, const ObjectModel& object)
      : options_(o), live_(hand, object, LiveOptionsOf(o)), pnh_("~") {
    if (!(o.annotated_rate >= 0.0 && o.annotated_rate <= 30.0))
      throw InputError("--annotated-rate: " + std::to_string(o.annotated_rate) +
                       ", expected [0, 30] Hz (0: no annotated image)");
    for (const std::string& set : live_.sets()) {
      pose_pub_.push_back(
          pnh_.advertise<geometry_msgs::PoseWithCovarianceStamped>(set + "/pose", 100));
      health_pub_.push_back(pnh_.advertise<std_msgs::String>(set + "/health", 10, true));
    }
    events_pub_ = pnh_.advertise<std_msgs::String>("events", 100);
    tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", 100);
    const auto no_delay = ::ros::TransportHints().tcpNoDelay();
    subs_.push_back(nh_.subscribe(o.joint_states, 1000, &Node::OnJointState, this, no_delay));
    subs_.push_back(nh_.subscribe("/tf", 1000, &Node::OnTf, this, no_delay));
    subs_.push_back(nh_.subscribe("/tf_static", 100, &Node::OnTfStatic, this, no_delay));
    if (!o.image.empty() && !o.compressed_image.empty())
      throw InputError("--image and --compressed-image: give one of them");
    if (!o.image.empty() || !o.compressed_image.empty()) {
      const std::string info = CameraInfoTopic(o);
      subs_.push_back(nh_.subscribe(info, 10, &Node::OnCameraInfo, this, no_delay));
      // Threaded: images are decoded on a thread of their own (a 640x480 PNG takes
      // milliseconds) and handed to the trackers by the next joint state, so that a joint state
      // never waits behind a decoding. Deterministic: decoded and fused in their callback.
      ::ros::NodeHandle& images = o.deterministic ? nh_ : image_nh_;
      if (!o.deterministic) image_nh_.setCallbackQueue(&image_queue_);
      if (!o.image.empty())
        subs_.push_back(images.subscribe(o.image, 4, &Node::OnImage, this, no_delay));
      else
        subs_.push_back(
            images.subscribe(o.compressed_image, 4, &Node::OnCompressedImage, this, no_delay));
      if (!o.deterministic) image_spinner_.start();
      if (o.annotated_rate > 0.0) {
        annotated_pub_ = pnh_.advertise<sensor_msgs::Image>("annotated", 2);
        annotator_ = std::make_unique<Annotator>(
            object, [this](const AnnotationRequest& r, const Image8& picture) {
              sensor_msgs::Image m;
              m.header.stamp = StampOf(r.stamp_ns);
              m.header.frame_id = r.frame_id;
              m.height = static_cast<std::uint32_t>(picture.height);
              m.width = static_cast<std::uint32_t>(picture.width);
              m.encoding = "rgb8";
              m.step = 3 * m.width;
              m.data.assign(picture.data.begin(), picture.data.end());
              annotated_pub_.publish(m);
            });
      }
      ROS_INFO("inhand: images from %s, intrinsics from %s",
               (o.image.empty() ? o.compressed_image : o.image).c_str(), info.c_str());
    }
    latency_us_.reserve(1 << 20);  // the first 2^20 joint states (35 min at 500 Hz) are timed
    ROS_INFO("inhand: sets %s, joints from %s, palm frame %s", o.sets.c_str(),
             o.joint_states.c_str(), live_.palm_frame().c_str());
  }

  // The figures at the end: each set's counts and the joint callback's latency.
  void Finish() {
    image_spinner_.stop();
    if (annotator_) {
      if (!annotator_->error().empty())
        ROS_ERROR("inhand: the annotated image: %s", annotator_->error().c_str());
      ROS_INFO("inhand: %ld annotated images published", annotator_->drawn());
    }
    for (const std::string& line : live_.Summary()) ROS_INFO("inhand: %s", line.c_str());
    std::vector<double> l = latency_us_;
    std::sort(l.begin(), l.end());
    const auto at = [&](double f) {
      return l.empty() ? 0.0 : l[std::min(l.size() - 1, static_cast<std::size_t>(f * l.size()))];
    };
    ROS_INFO(
        "inhand: %zu joint states, from arrival to publication p50 %.1f us, p99 %.1f us, "
        "max %.1f us",
        l.size(), at(0.5), at(0.99), l.empty() ? 0.0 : l.back());
    if (options_.stats_out.empty()) return;
    Json out;
    out["joint_states"] = l.size();
    out["latency_us"] = {{"p50", at(0.5)}, {"p99", at(0.99)}, {"max", l.empty() ? 0.0 : l.back()}};
    out["messages_not_used"] = not_used_.load();
    if (annotator_) out["annotated_images"] = annotator_->drawn();
    // The slowest joint states, by their order of arrival: where the tail comes from.
    std::vector<std::size_t> order(latency_us_.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    const std::size_t n = std::min<std::size_t>(10, order.size());
    std::partial_sort(
        order.begin(), order.begin() + static_cast<long>(n), order.end(),
        [&](std::size_t a, std::size_t b) { return latency_us_[a] > latency_us_[b]; });
    for (std::size_t k = 0; k < n; ++k) out["slowest"].push_back({order[k], latency_us_[order[k]]});
    for (std::size_t i = 0; i < live_.sets().size(); ++i) {
      const TrackerStats s = live_.tracker(i).stats();
      out["sets"][live_.sets()[i]] = {{"samples", s.samples},
                                      {"images_added", s.images_added},
                                      {"images_fused", s.images_fused},
                                      {"images_dropped_late", s.images_dropped_late},
                                      {"images_dropped_busy", s.images_dropped_busy},
                                      {"rewinds", s.rewinds}};
    }
    std::ofstream(options_.stats_out) << out.dump(2) << "\n";
  }

 private:
  NodeOptions options_;
  LiveTracking live_;
  ::ros::NodeHandle nh_, pnh_, image_nh_;
  ::ros::CallbackQueue image_queue_;
  ::ros::AsyncSpinner image_spinner_{1, &image_queue_};
  struct DecodedImage {
    Header header;
    Image8 image;
    std::string context;
  };
  std::mutex decoded_mutex_;
  std::vector<DecodedImage> decoded_, adding_;   // from the image thread to the joint states'
  static constexpr std::size_t kMaxDecoded = 4;  // more waiting: the oldest is not used
  std::vector<::ros::Publisher> pose_pub_, health_pub_;
  ::ros::Publisher events_pub_, tf_pub_;
  std::vector<::ros::Subscriber> subs_;
  std::vector<LivePose> poses_;
  std::vector<LiveEvent> events_;
  std::vector<double> latency_us_;
  std::atomic<long> not_used_{0};
  // The annotated image: the newest image used, drawn after the joint state that follows it.
  ::ros::Publisher annotated_pub_;
  std::unique_ptr<Annotator> annotator_;
  struct UsedImage {
    Header header;
    Image8 image;
    LiveImage camera;  // its camera pose and intrinsics, as the trackers were given them
  };
  std::optional<UsedImage> to_annotate_;
  std::int64_t last_annotated_ns_ = 0;

  // An image the trackers used: kept for the annotated image when one is due.
  void Used(const Header& header, const Image8& image) {
    if (!annotator_ || !live_.last_image() || live_.last_image()->stamp_ns != header.stamp_ns)
      return;
    const double period = 1.0 / options_.annotated_rate;
    if (last_annotated_ns_ != 0 && (header.stamp_ns - last_annotated_ns_) * 1e-9 < period - 1e-6)
      return;
    last_annotated_ns_ = header.stamp_ns;
    to_annotate_ = UsedImage{header, image, *live_.last_image()};
  }

  // After a joint state: the picture of the image kept, with every set's estimate now.
  void Annotate() {
    if (!to_annotate_) return;
    AnnotationRequest r;
    r.stamp_ns = to_annotate_->header.stamp_ns;
    r.frame_id = to_annotate_->header.frame_id;
    r.camera = std::move(to_annotate_->image);
    r.T_PC = to_annotate_->camera.T_PC;
    r.K = to_annotate_->camera.K;
    to_annotate_.reset();
    for (std::size_t i = 0; i < live_.sets().size(); ++i) {
      const Tracker& tracker = live_.tracker(i);
      app::EstimateRecord record;
      app::RecordContacts(tracker.trace(), record);
      app::RecordTrackerState(tracker, record);
      r.names.push_back(live_.sets()[i]);
      r.sets.push_back(app::CaptureSet(tracker, record, live_.T(r.stamp_ns), live_.hand()));
    }
    annotator_->Request(std::move(r));
  }

  void Complain(const std::string& error) {
    if (error.empty()) return;
    ++not_used_;
    ROS_WARN_THROTTLE(2.0, "inhand: %s", error.c_str());
  }

  void OnJointState(const sensor_msgs::JointState::ConstPtr& m) {
    const Clock::time_point arrival = Clock::now();
    JointStateMsg js;
    js.header = HeaderOf(m->header);
    js.name = m->name;
    js.position = m->position;
    js.effort = m->effort;
    {
      std::lock_guard<std::mutex> lock(decoded_mutex_);
      adding_.swap(decoded_);
    }
    for (const DecodedImage& d : adding_) {
      const std::string error = live_.OnImage(d.header, d.image, d.context);
      Complain(error);
      if (error.empty()) Used(d.header, d.image);
    }
    adding_.clear();
    poses_.clear();
    events_.clear();
    Complain(live_.OnJointState(js, options_.joint_states, poses_, events_));
    tf2_msgs::TFMessage tf;
    for (std::size_t k = 0; k < poses_.size(); ++k) {
      const LivePose& p = poses_[k];
      const std::size_t i = p.set;
      const std::string& set = live_.sets()[i];
      geometry_msgs::PoseWithCovarianceStamped out;
      out.header.stamp = StampOf(p.stamp_ns);
      out.header.frame_id = live_.palm_frame();
      const Quat q(p.T_PO.linear());
      out.pose.pose.position.x = p.T_PO.translation().x();
      out.pose.pose.position.y = p.T_PO.translation().y();
      out.pose.pose.position.z = p.T_PO.translation().z();
      out.pose.pose.orientation.w = q.w();
      out.pose.pose.orientation.x = q.x();
      out.pose.pose.orientation.y = q.y();
      out.pose.pose.orientation.z = q.z();
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c)
          out.pose.covariance[static_cast<std::size_t>(6 * r + c)] = p.covariance(r, c);
      pose_pub_[i].publish(out);
      geometry_msgs::TransformStamped t;
      t.header = out.header;
      t.child_frame_id = options_.object_frame_prefix + set;
      t.transform.translation.x = out.pose.pose.position.x;
      t.transform.translation.y = out.pose.pose.position.y;
      t.transform.translation.z = out.pose.pose.position.z;
      t.transform.rotation = out.pose.pose.orientation;
      tf.transforms.push_back(t);
      if (p.health_changed) {
        std_msgs::String h;
        h.data = Json{{"set", set},
                      {"stamp", p.stamp_ns * 1e-9},
                      {"state", HealthStateName(p.health.state)},
                      {"cause", HealthCauseName(p.health.cause)},
                      {"value", p.health.value},
                      {"since", p.health.since}}
                     .dump();
        health_pub_[i].publish(h);
      }
    }
    if (!tf.transforms.empty()) tf_pub_.publish(tf);
    for (const LiveEvent& e : events_) {
      std_msgs::String s;
      s.data = Json{{"set", live_.sets()[e.set]},
                    {"stamp", e.stamp_ns * 1e-9},
                    {"kind", EventKindName(e.event.kind)},
                    {"subject", e.event.subject},
                    {"value", e.event.value},
                    {"count", e.event.count},
                    {"duration", e.event.duration},
                    {"message", e.message}}
                   .dump();
      events_pub_.publish(s);
    }
    if (latency_us_.size() < latency_us_.capacity())
      latency_us_.push_back(
          std::chrono::duration<double, std::micro>(Clock::now() - arrival).count());
    Annotate();  // after the poses are out (not in the latency: it copies an image)
  }

  void OnTfMessage(const tf2_msgs::TFMessage& m, bool is_static) {
    TfMsg tf;
    for (const geometry_msgs::TransformStamped& t : m.transforms) {
      if (Ours(t.child_frame_id)) continue;
      StampedTransform s;
      s.header = HeaderOf(t.header);
      s.child_frame_id = t.child_frame_id;
      s.T.p = Vec3(t.transform.translation.x, t.transform.translation.y, t.transform.translation.z);
      try {
        const auto& r = t.transform.rotation;
        s.T.q = MessageQuaternion(r.w, r.x, r.y, r.z,
                                  (is_static ? "/tf_static " : "/tf ") + t.child_frame_id);
      } catch (const InputError& e) {
        Complain(e.what());
        continue;
      }
      tf.transforms.push_back(std::move(s));
    }
    Complain(live_.OnTf(tf, is_static));
  }
  // The frames this node publishes (PREFIX<set>) are not the robot's.
  bool Ours(const std::string& child) const {
    return std::any_of(live_.sets().begin(), live_.sets().end(), [&](const std::string& set) {
      return child == options_.object_frame_prefix + set;
    });
  }
  void OnTf(const tf2_msgs::TFMessage::ConstPtr& m) { OnTfMessage(*m, false); }
  void OnTfStatic(const tf2_msgs::TFMessage::ConstPtr& m) { OnTfMessage(*m, true); }

  void OnCameraInfo(const sensor_msgs::CameraInfo::ConstPtr& m) {
    CameraInfoMsg c;
    c.header = HeaderOf(m->header);
    c.width = m->width;
    c.height = m->height;
    c.distortion_model = m->distortion_model;
    c.d = m->D;
    std::copy(m->K.begin(), m->K.end(), c.k.begin());
    std::copy(m->R.begin(), m->R.end(), c.r.begin());
    std::copy(m->P.begin(), m->P.end(), c.p.begin());
    Complain(live_.OnCameraInfo(c, CameraInfoTopic(options_)));
  }

  void OnImage(const sensor_msgs::Image::ConstPtr& m) {
    ImageMsg im;
    im.header = HeaderOf(m->header);
    im.height = m->height;
    im.width = m->width;
    im.encoding = m->encoding;
    im.is_bigendian = m->is_bigendian;
    im.step = m->step;
    im.data = m->data;
    Fuse(
        im.header, [&] { return ImageOf(im, options_.image); }, options_.image);
  }

  void OnCompressedImage(const sensor_msgs::CompressedImage::ConstPtr& m) {
    CompressedImageMsg im;
    im.header = HeaderOf(m->header);
    im.format = m->format;
    im.data = m->data;
    Fuse(
        im.header, [&] { return ImageOf(im, options_.compressed_image); },
        options_.compressed_image);
  }

  // Decodes an image and fuses it now (deterministic) or hands it to the next joint state.
  template <typename Decode>
  void Fuse(const Header& header, const Decode& decode, const std::string& context) {
    Image8 image;
    try {
      image = decode();
    } catch (const InputError& e) {
      std::lock_guard<std::mutex> lock(decoded_mutex_);
      Complain(e.what());
      return;
    }
    if (options_.deterministic) {
      const std::string error = live_.OnImage(header, image, context);
      Complain(error);
      if (error.empty()) Used(header, image);
      return;
    }
    std::lock_guard<std::mutex> lock(decoded_mutex_);
    if (decoded_.size() >= kMaxDecoded) {
      decoded_.erase(decoded_.begin());
      Complain(context +
               ": images arrive faster than joint states take them; the oldest waiting "
               "one is not used");
    }
    decoded_.push_back({header, std::move(image), context});
  }
};

int Run(int argc, char** argv) {
  ::ros::init(argc, argv, "inhand");  // removes the ROS arguments (name:=value) from argv
  CLI::App app{
      "inhand's estimator as a ROS 1 node: joint states, a camera and TF in; the object's "
      "pose per modality set out"};
  NodeOptions o;
  // Each flag once: on the command line, and as the node's private parameter of the same name
  // with '_' for '-' (~start_frame for --start-frame), read when the flag is not given.
  std::vector<std::function<void(const ::ros::NodeHandle&)>> from_parameters;
  const auto option = [&](const char* flag, auto& value, const char* help) {
    CLI::Option* opt = nullptr;
    if constexpr (std::is_same_v<std::decay_t<decltype(value)>, bool>)
      opt = app.add_flag(flag, value, help);
    else
      opt = app.add_option(flag, value, help);
    from_parameters.push_back([opt, flag, &value](const ::ros::NodeHandle& pnh) {
      std::string name = std::string(flag).substr(2);
      std::replace(name.begin(), name.end(), '-', '_');
      if (opt->count() == 0) pnh.getParam(name, value);
    });
  };
  option("--hand", o.hand, "the hand's URDF (parameter ~hand)");
  option("--package", o.packages, "NAME=DIR for package:// URIs (repeatable)");
  option("--object", o.object, "the object's description (.json or .urdf)");
  option("--sets", o.sets, "modality sets, comma-separated: j, jt, ja, jf, jta, jtf (default jt)");
  option("--params", o.params_file, "tracker parameters (JSON file, as replay's params.json)");
  option("--params-json", o.params_json, "tracker parameters as JSON text");
  option("--joint-states", o.joint_states, "sensor_msgs/JointState topic (default /joint_states)");
  option("--effort-is", o.effort_is,
         "external: JointState.effort holds the external joint torques; none (default)");
  option("--image", o.image, "sensor_msgs/Image topic");
  option("--compressed-image", o.compressed_image,
         "sensor_msgs/CompressedImage topic (jpeg or png)");
  option("--camera-info", o.camera_info,
         "sensor_msgs/CameraInfo topic (default: camera_info beside the image)");
  option("--palm-frame", o.palm_frame, "TF frame of the palm (default: the URDF's root link)");
  option("--camera-frame", o.camera_frame,
         "TF frame of the camera (default: the images' frame_id)");
  option("--start", o.start,
         "the object's pose in the palm frame at the start: 'x y z qw qx qy qz' [m]");
  option("--start-frame", o.start_frame,
         "or: the TF frame whose pose at the first joint state is the start");
  option("--start-sigma", o.start_sigma,
         "'position orientation bias' σ at the start [m rad rad] (default 0.02 0.087 0.087)");
  option("--object-frame-prefix", o.object_frame_prefix,
         "TF child frames published: PREFIX<set> (default object_)");
  option("--time-origin", o.time_origin,
         "the stamp [s] that is t = 0 (default: the first joint state's)");
  option("--horizon", o.horizon,
         "[s] images captured longer ago than this are dropped (default 0.5)");
  option(
      "--deterministic", o.deterministic,
      "vision on the callback thread (bit-stable, slower joint rate while an image is processed)");
  option("--annotated-rate", o.annotated_rate,
         "[Hz] publish ~annotated (sensor_msgs/Image, rgb8): the camera image with every set's "
         "estimate drawn over it, at most this often (default 0: not published)");
  option("--stats-out", o.stats_out, "write the counts and latencies here (JSON) at the end");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    const ::ros::NodeHandle pnh("~");
    for (const auto& fill : from_parameters) fill(pnh);
    if (o.hand.empty()) throw InputError("--hand (or ~hand): the hand's URDF is needed");
    if (o.object.empty()) throw InputError("--object (or ~object): the object is needed");
    HandLoadOptions hand_options;
    for (const std::string& p : o.packages) hand_options.packages.AddSpec(p);
    hand_options.load_visual_meshes = true;
    const HandModel hand = LoadHandModel(o.hand, hand_options);
    const ObjectModel object = LoadObjectModel(o.object, hand_options.packages);
    Node node(o, hand, object);
    ::ros::spin();
    node.Finish();
  } catch (const InputError& e) {
    std::cerr << "inhand_ros_node: " << e.what() << "\n";
    return 2;
  }
  return 0;
}

}  // namespace
}  // namespace inhand::ros

int main(int argc, char** argv) { return inhand::ros::Run(argc, argv); }
