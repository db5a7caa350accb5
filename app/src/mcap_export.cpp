#include "mcap_export.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/ros/mcap_writer.hpp"

namespace inhand::app {

namespace {

using Json = nlohmann::json;

// JSON schemas of the foxglove message types used (the fields Foxglove reads).
const Json kTime = {
    {"type", "object"},
    {"properties", {{"sec", {{"type", "integer"}}}, {"nsec", {{"type", "integer"}}}}}};
const Json kColor = {{"type", "object"},
                     {"properties",
                      {{"r", {{"type", "number"}}},
                       {"g", {{"type", "number"}}},
                       {"b", {{"type", "number"}}},
                       {"a", {{"type", "number"}}}}}};
const Json kPoint2 = {{"type", "object"},
                      {"properties", {{"x", {{"type", "number"}}}, {"y", {{"type", "number"}}}}}};

Json Schema(const std::string& title, const Json& properties) {
  return {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
          {"title", title},
          {"type", "object"},
          {"properties", properties}};
}

Json Time(double t) {
  const auto ns = std::llround(t * 1e9);
  return {{"sec", ns / 1000000000}, {"nsec", ns % 1000000000}};
}
Json PoseJson(const Transform& T) {
  const Quat q(T.linear());
  const Vec3& p = T.translation();
  return {{"position", {{"x", p.x()}, {"y", p.y()}, {"z", p.z()}}},
          {"orientation", {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}}};
}
Json ColorJson(const Rgb& c, double a = 1.0) {
  return {{"r", c.r / 255.0}, {"g", c.g / 255.0}, {"b", c.b / 255.0}, {"a", a}};
}

// ROS 2's serialization (XCDR1, little endian): the encapsulation header 00 01 00 00, then each
// primitive aligned to its size, counted from the end of that header; strings with their length
// (the NUL included) and a NUL, sequences with their count. The host is little endian (x86-64,
// arm64).
class Cdr {
 public:
  Cdr() : bytes_("\x00\x01\x00\x00", 4) {}
  template <class T>
  Cdr& Put(T v) {
    Align(sizeof(T));
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    bytes_.append(b, sizeof(T));
    return *this;
  }
  Cdr& String(const std::string& s) {
    Put<std::uint32_t>(static_cast<std::uint32_t>(s.size() + 1));
    bytes_ += s;
    bytes_.push_back('\0');
    return *this;
  }
  Cdr& Bytes(const std::string& b) {  // uint8[]
    Put<std::uint32_t>(static_cast<std::uint32_t>(b.size()));
    bytes_ += b;
    return *this;
  }
  Cdr& Time(double t) {  // builtin_interfaces/Time: sec may be negative, nanosec in [0, 1e9)
    const long long ns = std::llround(t * 1e9);
    const long long sec = ns >= 0 ? ns / 1000000000 : -((-ns + 999999999) / 1000000000);
    return Put<std::int32_t>(static_cast<std::int32_t>(sec))
        .Put<std::uint32_t>(static_cast<std::uint32_t>(ns - sec * 1000000000));
  }
  Cdr& Pose(const Transform& T) {  // translation (x y z), then the quaternion (x y z w)
    const Quat q(T.linear());
    const Vec3& p = T.translation();
    for (const double v : {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()}) Put<double>(v);
    return *this;
  }
  const std::string& bytes() const { return bytes_; }

 private:
  void Align(std::size_t n) { bytes_.append((n - (bytes_.size() - 4) % n) % n, '\0'); }
  std::string bytes_;
};

// ros2msg definitions of the foxglove messages written as CDR: the message's fields, then each
// type it uses after a separator line, as ROS 2 tools concatenate them.
const std::string kSeparator = "\n" + std::string(80, '=') + "\n";
const std::string kTimeMsg = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec";
const std::string kQuaternionMsg =
    "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w";
const std::string kPoseInFrameMsg =
    "builtin_interfaces/Time timestamp\nstring frame_id\ngeometry_msgs/Pose pose" + kSeparator +
    kTimeMsg + kSeparator +
    "MSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion "
    "orientation" +
    kSeparator + "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z" + kSeparator +
    kQuaternionMsg;
const std::string kFrameTransformMsg =
    "builtin_interfaces/Time timestamp\nstring parent_frame_id\nstring child_frame_id\n"
    "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation" +
    kSeparator + kTimeMsg + kSeparator +
    "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z" + kSeparator + kQuaternionMsg;
const std::string kCompressedImageMsg =
    "builtin_interfaces/Time timestamp\nstring frame_id\nuint8[] data\nstring format" + kSeparator +
    kTimeMsg;

std::string FrameTransformCdr(double t, const std::string& parent, const std::string& child,
                              const Transform& T) {
  return Cdr().Time(t).String(parent).String(child).Pose(T).bytes();
}

std::uint64_t LogTime(double t) {
  return static_cast<std::uint64_t>(std::max<long long>(0, std::llround(t * 1e9)));
}

}  // namespace

McapExport::McapExport(const std::string& path, const SessionPlayer& player)
    : p_(player), w_(std::make_unique<ros::McapWriter>(path)) {
  const auto schema = [&](const std::string& name, const Json& properties) {
    return w_->AddSchema(name, "jsonschema", Schema(name, properties).dump());
  };
  const std::uint16_t pose =
      w_->AddSchema("foxglove_msgs/msg/PoseInFrame", "ros2msg", kPoseInFrameMsg);
  for (const ModalitySet& s : p_.sets())
    pose_channels_.push_back(w_->AddChannel("/inhand/pose/" + s.name, pose, "cdr"));
  tf_ = w_->AddChannel(
      "/tf", w_->AddSchema("foxglove_msgs/msg/FrameTransform", "ros2msg", kFrameTransformMsg),
      "cdr");
  errors_ = w_->AddChannel(
      "/inhand/errors",
      schema("inhand.Errors", {{"t", {{"type", "number"}}}, {"sets", {{"type", "object"}}}}),
      "json");
  if (p_.session().info().camera) {
    image_ = w_->AddChannel(
        "/camera/image",
        w_->AddSchema("foxglove_msgs/msg/CompressedImage", "ros2msg", kCompressedImageMsg), "cdr");
    annotations_ =
        w_->AddChannel("/camera/annotations",
                       schema("foxglove.ImageAnnotations", {{"circles", {{"type", "array"}}},
                                                            {"points", {{"type", "array"}}},
                                                            {"texts", {{"type", "array"}}}}),
                       "json");
  }
  events_ = w_->AddChannel("/inhand/events",
                           schema("foxglove.Log", {{"timestamp", kTime},
                                                   {"level", {{"type", "integer"}}},
                                                   {"message", {{"type", "string"}}},
                                                   {"name", {{"type", "string"}}},
                                                   {"file", {{"type", "string"}}},
                                                   {"line", {{"type", "integer"}}},
                                                   {"t", {{"type", "number"}}},
                                                   {"kind", {{"type", "string"}}},
                                                   {"subject", {{"type", "string"}}},
                                                   {"value", {{"type", "number"}}},
                                                   {"count", {{"type", "integer"}}},
                                                   {"duration", {{"type", "number"}}}}),
                           "json");
  scene_ = w_->AddChannel("/inhand/contacts",
                          schema("foxglove.SceneUpdate", {{"deletions", {{"type", "array"}}},
                                                          {"entities", {{"type", "array"}}}}),
                          "json");
}

McapExport::~McapExport() = default;

void McapExport::AddSample(int k, const EstimateRecord* records, int frame) {
  const Session& s = p_.session();
  const double t = s.t(k);
  const std::uint64_t log = LogTime(t);
  Json errors = {{"t", t}, {"sets", Json::object()}};
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    const EstimateRecord& r = records[i];
    const std::string& name = p_.sets()[i].name;
    w_->Write(pose_channels_[i], log, Cdr().Time(t).String("palm").Pose(r.T_PO).bytes());
    w_->Write(tf_, log, FrameTransformCdr(t, "palm", "object_" + name, r.T_PO));
    Json e = {
        {"sigma_position_mm",
         {r.sigma_position.x() * 1000, r.sigma_position.y() * 1000, r.sigma_position.z() * 1000}},
        {"sigma_orientation_deg",
         {r.sigma_orientation.x() * 180 / M_PI, r.sigma_orientation.y() * 180 / M_PI,
          r.sigma_orientation.z() * 180 / M_PI}},
        {"constraints", r.constraints},
        {"penetration_mm", r.penetration * 1000},
        {"unexplained_torque_Nm", r.unexplained_torque},
        {"slipping", r.slipping},
        {"features_lost", r.memory.features_lost()},
        {"tags_elsewhere", r.memory.tag_disagreements > 0},
        {"health", HealthStateName(r.health.state)},
        {"health_cause", HealthCauseName(r.health.cause)},
        {"health_value", r.health.value},
        {"health_since", r.health.since}};
    if (r.health.state != HealthState::kOk)
      e["health_message"] = HealthMessage(r.health, p_.models().hand);
    if (r.press.pressing) e["pressing_gap_mm"] = r.press.gap * 1000;
    if (std::isfinite(r.position_error)) {
      e["position_error_mm"] = r.position_error * 1000;
      e["orientation_error_deg"] = r.orientation_error * 180 / M_PI;
      e["nees"] = r.nees;
    }
    errors["sets"][name] = e;
    AddEvents(i, r.events, t);
  }
  w_->Write(errors_, log, errors.dump());
  if (s.has_groundtruth())
    w_->Write(tf_, log, FrameTransformCdr(t, "palm", "object_truth", s.GroundTruthAt(t)));
  if (frame >= 0 && s.info().camera) AddFrame(frame, t);
}

void McapExport::AddEvents(std::size_t i, const std::vector<TrackerEvent>& events, double t) {
  const HandModel& hand = p_.models().hand;
  for (const TrackerEvent& ev : events) {
    // foxglove.Log's levels: 2 info, 3 warning (inconsistent, NEES beyond its bound), 4 error
    // (lost).
    int level = 2;
    if (ev.kind == EventKind::kNeesBeyondBound ||
        (ev.kind == EventKind::kHealth && ev.health.state == HealthState::kInconsistent))
      level = 3;
    if (ev.kind == EventKind::kHealth && ev.health.state == HealthState::kLost) level = 4;
    w_->Write(events_, LogTime(t),
              Json{{"timestamp", Time(ev.t)},
                   {"level", level},
                   {"message", std::string(EventKindName(ev.kind)) + ": " + EventMessage(ev, hand)},
                   {"name", "inhand/" + p_.sets()[i].name},
                   {"file", ""},
                   {"line", 0},
                   {"t", ev.t},
                   {"kind", EventKindName(ev.kind)},
                   {"subject", EventSubject(ev, hand)},
                   {"value", ev.value},
                   {"count", ev.count},
                   {"duration", ev.duration}}
                  .dump());
  }
}

void McapExport::AddFrame(int frame, double t) {
  const Session& s = p_.session();
  const CameraFrame& f = s.camera_frames()[static_cast<std::size_t>(frame)];
  const std::uint64_t log = LogTime(f.t);
  w_->Write(tf_, log, FrameTransformCdr(f.t, "palm", "camera", f.T_PC));
  // The session's image file as it is (PNG or JPEG), never decoded or re-encoded.
  std::ifstream in(s.Resolve(f.image), std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  const std::string ext = f.image.substr(f.image.rfind('.') + 1);
  w_->Write(image_, log,
            Cdr()
                .Time(f.t)
                .String("camera")
                .Bytes(bytes.str())
                .String(ext == "jpg" ? "jpeg" : ext)
                .bytes());

  // The overlays in image coordinates: each set's object origin and contact points, its
  // features (measured -> predicted), projected through the camera.
  const Intrinsics& K = *s.info().camera;
  const Transform T_CP = f.T_PC.inverse();
  Json circles = Json::array(), points = Json::array(), texts = Json::array();
  const auto project = [&](const Vec3& X_P) -> std::optional<Vec2> {
    const Vec3 X_C = T_CP * X_P;
    if (X_C.z() <= 1e-6) return std::nullopt;
    return K.Distort(K.Project(X_C));
  };
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    const Rgb& c = p_.sets()[i].colour;
    const Filter& filter = p_.tracker(i).filter();
    if (const auto o = project(p_.last(i).T_PO.translation())) {
      circles.push_back({{"timestamp", Time(f.t)},
                         {"position", {{"x", o->x()}, {"y", o->y()}}},
                         {"diameter", 12.0},
                         {"thickness", 2.0},
                         {"fill_color", ColorJson(c, 0.0)},
                         {"outline_color", ColorJson(c)}});
      texts.push_back({{"timestamp", Time(f.t)},
                       {"position", {{"x", o->x() + 8}, {"y", o->y() - 8}}},
                       {"text", p_.sets()[i].name},
                       {"font_size", 14.0},
                       {"text_color", ColorJson(c)},
                       {"background_color", ColorJson(Rgb{255, 255, 255}, 0.6)}});
    }
    Json contact_points = Json::array();
    for (const auto& contact : filter.trace().contacts)
      if (const auto u = project(contact.c_o_P))
        contact_points.push_back({{"x", u->x()}, {"y", u->y()}});
    if (!contact_points.empty())
      points.push_back({{"timestamp", Time(f.t)},
                        {"type", 1},
                        {"points", contact_points},
                        {"outline_color", ColorJson(c)},
                        {"thickness", 6.0}});
    Json lines = Json::array();
    for (const auto& v : filter.trace().visual) {
      const Vec2 a = K.Distort(v.measured), b = K.Distort(v.predicted);
      lines.push_back({{"x", a.x()}, {"y", a.y()}});
      lines.push_back({{"x", b.x()}, {"y", b.y()}});
    }
    if (!lines.empty())
      points.push_back({{"timestamp", Time(f.t)},
                        {"type", 4},
                        {"points", lines},
                        {"outline_color", ColorJson(c)},
                        {"thickness", 1.5}});  // 4: LINE_LIST
  }
  w_->Write(annotations_, log,
            Json{{"circles", circles}, {"points", points}, {"texts", texts}}.dump());

  // Contacts and forces in 3-D: a sphere per contact, an arrow per force (1 cm per newton).
  Json entities = Json::array();
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    const Rgb& c = p_.sets()[i].colour;
    Json spheres = Json::array(), arrows = Json::array();
    for (const auto& contact : p_.tracker(i).filter().trace().contacts) {
      spheres.push_back({{"pose", PoseJson(MakeTransform(contact.c_o_P, Quat::Identity()))},
                         {"size", {{"x", 0.004}, {"y", 0.004}, {"z", 0.004}}},
                         {"color", ColorJson(c)}});
      const double n = contact.force_P.norm();
      if (n > 1e-6)
        arrows.push_back({{"pose", PoseJson(MakeTransform(
                                       contact.c_o_P,
                                       Quat::FromTwoVectors(Vec3::UnitX(), contact.force_P / n)))},
                          {"shaft_length", 0.01 * n},
                          {"shaft_diameter", 0.0015},
                          {"head_length", 0.004},
                          {"head_diameter", 0.003},
                          {"color", ColorJson(c)}});
    }
    entities.push_back({{"timestamp", Time(t)},
                        {"frame_id", "palm"},
                        {"id", "contacts_" + p_.sets()[i].name},
                        {"lifetime", {{"sec", 0}, {"nsec", 0}}},
                        {"frame_locked", false},
                        {"spheres", spheres},
                        {"arrows", arrows}});
  }
  w_->Write(scene_, log, Json{{"deletions", Json::array()}, {"entities", entities}}.dump());
}

void McapExport::Close() { w_->Close(); }

}  // namespace inhand::app
