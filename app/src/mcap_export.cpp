#include "mcap_export.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/ros/mcap_writer.hpp"

namespace inhand::app {

namespace {

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
  Cdr& Length(std::size_t n) {  // of a sequence (elements) or a string (bytes with the NUL)
    return Put<std::uint32_t>(static_cast<std::uint32_t>(n));
  }
  Cdr& String(const std::string& s) {
    Length(s.size() + 1);
    bytes_ += s;
    bytes_.push_back('\0');
    return *this;
  }
  Cdr& Bytes(const std::string& b) {  // uint8[]
    Length(b.size());
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
  Cdr& Point2(const Vec2& u) { return Put<double>(u.x()).Put<double>(u.y()); }
  Cdr& Color(const Rgb& c, double a = 1.0) {  // foxglove_msgs/Color, components in [0, 1]
    return Put<double>(c.r / 255.0)
        .Put<double>(c.g / 255.0)
        .Put<double>(c.b / 255.0)
        .Put<double>(a);
  }
  const std::string& bytes() const { return bytes_; }

 private:
  void Align(std::size_t n) { bytes_.append((n - (bytes_.size() - 4) % n) % n, '\0'); }
  std::string bytes_;
};

// ros2msg definitions, written as ROS 2 tools concatenate them: the message's own fields, then
// each type it uses after a separator line ("MSG: package/Type"). The foxglove_msgs types are the
// viewers' own (their Image, 3-D and Log panels read them); inhand_msgs are this program's: the
// per-set state at joint rate and the tracker's events, fields named as in summary.json and
// events.csv.
const std::string kSeparator = "\n" + std::string(80, '=') + "\n";
const std::map<std::string, std::string> kTypes = {
    {"builtin_interfaces/Time", "int32 sec\nuint32 nanosec"},
    {"builtin_interfaces/Duration", "int32 sec\nuint32 nanosec"},
    {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z"},
    {"geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z"},
    {"geometry_msgs/Quaternion", "float64 x\nfloat64 y\nfloat64 z\nfloat64 w"},
    {"geometry_msgs/Pose", "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation"},
    {"foxglove_msgs/Color", "float64 r\nfloat64 g\nfloat64 b\nfloat64 a"},
    {"foxglove_msgs/Point2", "float64 x\nfloat64 y"},
    {"foxglove_msgs/CircleAnnotation",
     "builtin_interfaces/Time timestamp\nfoxglove_msgs/Point2 position\nfloat64 diameter\n"
     "float64 thickness\nfoxglove_msgs/Color fill_color\nfoxglove_msgs/Color outline_color"},
    {"foxglove_msgs/PointsAnnotation",
     "builtin_interfaces/Time timestamp\nuint8 UNKNOWN=0\nuint8 POINTS=1\nuint8 LINE_LOOP=2\n"
     "uint8 LINE_STRIP=3\nuint8 LINE_LIST=4\nuint8 type\nfoxglove_msgs/Point2[] points\n"
     "foxglove_msgs/Color outline_color\nfoxglove_msgs/Color[] outline_colors\n"
     "foxglove_msgs/Color fill_color\nfloat64 thickness"},
    {"foxglove_msgs/TextAnnotation",
     "builtin_interfaces/Time timestamp\nfoxglove_msgs/Point2 position\nstring text\n"
     "float64 font_size\nfoxglove_msgs/Color text_color\nfoxglove_msgs/Color background_color"},
    {"foxglove_msgs/KeyValuePair", "string key\nstring value"},
    {"foxglove_msgs/SceneEntityDeletion",
     "builtin_interfaces/Time timestamp\nuint8 MATCHING_ID=0\nuint8 ALL=1\nuint8 type\nstring id"},
    {"foxglove_msgs/SceneEntity",
     "builtin_interfaces/Time timestamp\nstring frame_id\nstring id\n"
     "builtin_interfaces/Duration lifetime\nbool frame_locked\n"
     "foxglove_msgs/KeyValuePair[] metadata\nfoxglove_msgs/ArrowPrimitive[] arrows\n"
     "foxglove_msgs/CubePrimitive[] cubes\nfoxglove_msgs/SpherePrimitive[] spheres\n"
     "foxglove_msgs/CylinderPrimitive[] cylinders\nfoxglove_msgs/LinePrimitive[] lines\n"
     "foxglove_msgs/TriangleListPrimitive[] triangles\nfoxglove_msgs/TextPrimitive[] texts\n"
     "foxglove_msgs/ModelPrimitive[] models"},
    {"foxglove_msgs/ArrowPrimitive",
     "geometry_msgs/Pose pose\nfloat64 shaft_length\nfloat64 shaft_diameter\n"
     "float64 head_length\nfloat64 head_diameter\nfoxglove_msgs/Color color"},
    {"foxglove_msgs/CubePrimitive",
     "geometry_msgs/Pose pose\ngeometry_msgs/Vector3 size\nfoxglove_msgs/Color color"},
    {"foxglove_msgs/SpherePrimitive",
     "geometry_msgs/Pose pose\ngeometry_msgs/Vector3 size\nfoxglove_msgs/Color color"},
    {"foxglove_msgs/CylinderPrimitive",
     "geometry_msgs/Pose pose\ngeometry_msgs/Vector3 size\nfloat64 bottom_scale\n"
     "float64 top_scale\nfoxglove_msgs/Color color"},
    {"foxglove_msgs/LinePrimitive",
     "uint8 LINE_STRIP=0\nuint8 LINE_LOOP=1\nuint8 LINE_LIST=2\nuint8 type\n"
     "geometry_msgs/Pose pose\nfloat64 thickness\nbool scale_invariant\n"
     "geometry_msgs/Point[] points\nfoxglove_msgs/Color color\nfoxglove_msgs/Color[] colors\n"
     "uint32[] indices"},
    {"foxglove_msgs/TriangleListPrimitive",
     "geometry_msgs/Pose pose\ngeometry_msgs/Point[] points\nfoxglove_msgs/Color color\n"
     "foxglove_msgs/Color[] colors\nuint32[] indices"},
    {"foxglove_msgs/TextPrimitive",
     "geometry_msgs/Pose pose\nbool billboard\nfloat64 font_size\nbool scale_invariant\n"
     "foxglove_msgs/Color color\nstring text"},
    {"foxglove_msgs/ModelPrimitive",
     "geometry_msgs/Pose pose\ngeometry_msgs/Vector3 scale\nfoxglove_msgs/Color color\n"
     "bool override_color\nstring url\nstring media_type\nuint8[] data"},
    {"inhand_msgs/SetState",
     "# one modality set at one joint sample; NaN where a value does not apply (errors and NEES\n"
     "# without ground truth, the gap when no finger presses)\n"
     "string set\nfloat64[3] sigma_position_mm\nfloat64[3] sigma_orientation_deg\n"
     "int32 constraints\nfloat64 penetration_mm\nfloat64 unexplained_torque_nm\nbool slipping\n"
     "bool features_lost\nbool tags_elsewhere\nstring health\nstring health_cause\n"
     "float64 health_value\nfloat64 health_since\nstring health_message\nbool pressing\n"
     "float64 pressing_gap_mm\nfloat64 position_error_mm\nfloat64 orientation_error_deg\n"
     "float64 nees"},
};

// The definition of a message with `fields`, followed by every type it uses, directly or not.
std::string Definition(const std::string& fields) {
  std::string out = fields;
  std::set<std::string> done;
  std::vector<std::string> todo = {fields};
  while (!todo.empty()) {
    const std::string text = todo.back();
    todo.pop_back();
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
      const std::size_t space = line.find(' ');
      if (line.empty() || line[0] == '#' || space == std::string::npos) continue;
      std::string type = line.substr(0, space);
      type = type.substr(0, type.find('['));
      const auto it = kTypes.find(type);
      if (it == kTypes.end() || !done.insert(type).second) continue;
      out += kSeparator + "MSG: " + type + "\n" + it->second;
      todo.push_back(it->second);
    }
  }
  return out;
}

const std::string kPoseInFrameMsg =
    Definition("builtin_interfaces/Time timestamp\nstring frame_id\ngeometry_msgs/Pose pose");
const std::string kFrameTransformMsg = Definition(
    "builtin_interfaces/Time timestamp\nstring parent_frame_id\nstring child_frame_id\n"
    "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation");
const std::string kCompressedImageMsg =
    Definition("builtin_interfaces/Time timestamp\nstring frame_id\nuint8[] data\nstring format");
const std::string kImageAnnotationsMsg = Definition(
    "foxglove_msgs/CircleAnnotation[] circles\nfoxglove_msgs/PointsAnnotation[] points\n"
    "foxglove_msgs/TextAnnotation[] texts");
const std::string kSceneUpdateMsg = Definition(
    "foxglove_msgs/SceneEntityDeletion[] deletions\nfoxglove_msgs/SceneEntity[] entities");
const std::string kLogMsg = Definition(
    "builtin_interfaces/Time timestamp\nuint8 UNKNOWN=0\nuint8 DEBUG=1\nuint8 INFO=2\n"
    "uint8 WARNING=3\nuint8 ERROR=4\nuint8 FATAL=5\nuint8 level\nstring message\nstring name\n"
    "string file\nuint32 line");
const std::string kStateMsg =
    Definition("builtin_interfaces/Time timestamp\ninhand_msgs/SetState[] sets");
const std::string kEventMsg = Definition(
    "# a row of events.csv\nbuiltin_interfaces/Time timestamp\nstring set\nstring kind\n"
    "string subject\nfloat64 value\nint32 count\nfloat64 duration\nstring message\n"
    "uint8 level");

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
  const auto channel = [&](const std::string& topic, const std::string& type,
                           const std::string& definition) {
    return w_->AddChannel(topic, w_->AddSchema(type, "ros2msg", definition), "cdr");
  };
  const std::uint16_t pose =
      w_->AddSchema("foxglove_msgs/msg/PoseInFrame", "ros2msg", kPoseInFrameMsg);
  for (const ModalitySet& s : p_.sets())
    pose_channels_.push_back(w_->AddChannel("/inhand/pose/" + s.name, pose, "cdr"));
  tf_ = channel("/tf", "foxglove_msgs/msg/FrameTransform", kFrameTransformMsg);
  errors_ = channel("/inhand/errors", "inhand_msgs/msg/State", kStateMsg);
  if (p_.session().info().camera) {
    image_ = channel("/camera/image", "foxglove_msgs/msg/CompressedImage", kCompressedImageMsg);
    annotations_ =
        channel("/camera/annotations", "foxglove_msgs/msg/ImageAnnotations", kImageAnnotationsMsg);
  }
  events_ = channel("/inhand/events", "inhand_msgs/msg/Event", kEventMsg);
  log_ = channel("/inhand/log", "foxglove_msgs/msg/Log", kLogMsg);
  scene_ = channel("/inhand/contacts", "foxglove_msgs/msg/SceneUpdate", kSceneUpdateMsg);
}

McapExport::~McapExport() = default;

void McapExport::AddSample(int k, const EstimateRecord* records, int frame) {
  const Session& s = p_.session();
  const double t = s.t(k);
  const std::uint64_t log = LogTime(t);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Cdr state;
  state.Time(t).Length(p_.sets().size());
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    const EstimateRecord& r = records[i];
    const std::string& name = p_.sets()[i].name;
    w_->Write(pose_channels_[i], log, Cdr().Time(t).String("palm").Pose(r.T_PO).bytes());
    w_->Write(tf_, log, FrameTransformCdr(t, "palm", "object_" + name, r.T_PO));
    const bool truth = std::isfinite(r.position_error);
    state.String(name);
    for (int a = 0; a < 3; ++a) state.Put<double>(r.sigma_position[a] * 1000);
    for (int a = 0; a < 3; ++a) state.Put<double>(r.sigma_orientation[a] * 180 / M_PI);
    state.Put<std::int32_t>(r.constraints)
        .Put<double>(r.penetration * 1000)
        .Put<double>(r.unexplained_torque)
        .Put<std::uint8_t>(r.slipping)
        .Put<std::uint8_t>(r.memory.features_lost())
        .Put<std::uint8_t>(r.memory.tag_disagreements > 0)
        .String(HealthStateName(r.health.state))
        .String(HealthCauseName(r.health.cause))
        .Put<double>(r.health.value)
        .Put<double>(r.health.since)
        .String(r.health.state != HealthState::kOk ? HealthMessage(r.health, p_.models().hand)
                                                   : std::string())
        .Put<std::uint8_t>(r.press.pressing)
        .Put<double>(r.press.pressing ? r.press.gap * 1000 : nan)
        .Put<double>(truth ? r.position_error * 1000 : nan)
        .Put<double>(truth ? r.orientation_error * 180 / M_PI : nan)
        .Put<double>(truth ? r.nees : nan);
    AddEvents(i, r.events, t);
  }
  w_->Write(errors_, log, state.bytes());
  if (s.has_groundtruth())
    w_->Write(tf_, log, FrameTransformCdr(t, "palm", "object_truth", s.GroundTruthAt(t)));
  if (frame >= 0 && s.info().camera) AddFrame(frame, t);
}

void McapExport::AddEvents(std::size_t i, const std::vector<TrackerEvent>& events, double t) {
  const HandModel& hand = p_.models().hand;
  for (const TrackerEvent& ev : events) {
    // foxglove_msgs/Log's levels: 2 info, 3 warning (inconsistent, NEES beyond its bound, a start
    // inside the object), 4 error (lost).
    std::uint8_t level = 2;
    if (ev.kind == EventKind::kNeesBeyondBound || ev.kind == EventKind::kStartSettled ||
        (ev.kind == EventKind::kHealth && ev.health.state == HealthState::kInconsistent))
      level = 3;
    if (ev.kind == EventKind::kHealth && ev.health.state == HealthState::kLost) level = 4;
    const std::string kind = EventKindName(ev.kind), message = EventMessage(ev, hand);
    const std::string& set = p_.sets()[i].name;
    w_->Write(events_, LogTime(t),
              Cdr()
                  .Time(ev.t)
                  .String(set)
                  .String(kind)
                  .String(EventSubject(ev, hand))
                  .Put<double>(ev.value)
                  .Put<std::int32_t>(ev.count)
                  .Put<double>(ev.duration)
                  .String(message)
                  .Put<std::uint8_t>(level)
                  .bytes());
    w_->Write(log_, LogTime(t),
              Cdr()
                  .Time(ev.t)
                  .Put<std::uint8_t>(level)
                  .String(kind + ": " + message)
                  .String("inhand/" + set)
                  .String("")
                  .Put<std::uint32_t>(0)
                  .bytes());
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

  // The overlays in image coordinates: each set's object origin (a circle and its name), its
  // contact points and its features (measured -> predicted, a line list), projected through the
  // camera.
  const Intrinsics& K = *s.info().camera;
  const Transform T_CP = f.T_PC.inverse();
  const auto project = [&](const Vec3& X_P) -> std::optional<Vec2> {
    const Vec3 X_C = T_CP * X_P;
    if (X_C.z() <= 1e-6) return std::nullopt;
    return K.Distort(K.Project(X_C));
  };
  struct Points {
    std::uint8_t type;  // 1 POINTS, 4 LINE_LIST
    std::vector<Vec2> points;
    Rgb colour;
    double thickness;
  };
  std::vector<std::pair<Vec2, std::size_t>> origins;  // with the set's index
  std::vector<Points> points;
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    const Rgb& c = p_.sets()[i].colour;
    const Filter& filter = p_.tracker(i).filter();
    if (const auto o = project(p_.last(i).T_PO.translation())) origins.emplace_back(*o, i);
    Points contacts{1, {}, c, 6.0}, lines{4, {}, c, 1.5};
    for (const auto& contact : filter.trace().contacts)
      if (const auto u = project(contact.c_o_P)) contacts.points.push_back(*u);
    for (const auto& v : filter.trace().visual) {
      lines.points.push_back(K.Distort(v.measured));
      lines.points.push_back(K.Distort(v.predicted));
    }
    for (Points* p : {&contacts, &lines})
      if (!p->points.empty()) points.push_back(std::move(*p));
  }
  const Rgb white{255, 255, 255};
  Cdr annotations;
  annotations.Length(origins.size());
  for (const auto& [o, i] : origins)
    annotations.Time(f.t)
        .Point2(o)
        .Put<double>(12.0)
        .Put<double>(2.0)
        .Color(p_.sets()[i].colour, 0.0)
        .Color(p_.sets()[i].colour);
  annotations.Length(points.size());
  for (const Points& p : points) {
    annotations.Time(f.t).Put<std::uint8_t>(p.type).Length(p.points.size());
    for (const Vec2& u : p.points) annotations.Point2(u);
    annotations.Color(p.colour)
        .Length(0)  // outline_colors
        .Color(p.colour, 0.0)
        .Put<double>(p.thickness);
  }
  annotations.Length(origins.size());
  for (const auto& [o, i] : origins)
    annotations.Time(f.t)
        .Point2(o + Vec2(8, -8))
        .String(p_.sets()[i].name)
        .Put<double>(14.0)
        .Color(p_.sets()[i].colour)
        .Color(white, 0.6);
  w_->Write(annotations_, log, annotations.bytes());

  // Contacts and forces in 3-D, an entity per set: a 4 mm sphere per contact, an arrow per force
  // (1 cm per newton).
  Cdr scene;
  scene.Length(0);  // deletions
  scene.Length(p_.sets().size());
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    const Rgb& c = p_.sets()[i].colour;
    const auto& contacts = p_.tracker(i).filter().trace().contacts;
    scene.Time(t)
        .String("palm")
        .String("contacts_" + p_.sets()[i].name)
        .Put<std::int32_t>(0)
        .Put<std::uint32_t>(0)  // lifetime 0: until replaced
        .Put<std::uint8_t>(0)   // frame_locked
        .Length(0);             // metadata
    std::uint32_t arrows = 0;
    for (const auto& contact : contacts) arrows += contact.force_P.norm() > 1e-6;
    scene.Length(arrows);
    for (const auto& contact : contacts) {
      const double n = contact.force_P.norm();
      if (n <= 1e-6) continue;
      scene
          .Pose(MakeTransform(contact.c_o_P,
                              Quat::FromTwoVectors(Vec3::UnitX(), contact.force_P / n)))
          .Put<double>(0.01 * n)
          .Put<double>(0.0015)
          .Put<double>(0.004)
          .Put<double>(0.003)
          .Color(c);
    }
    scene.Length(0);  // cubes
    scene.Length(contacts.size());
    for (const auto& contact : contacts)
      scene.Pose(MakeTransform(contact.c_o_P, Quat::Identity()))
          .Put<double>(0.004)
          .Put<double>(0.004)
          .Put<double>(0.004)
          .Color(c);
    for (int empty = 0; empty < 5; ++empty)  // cylinders, lines, triangles, texts, models
      scene.Length(0);
  }
  w_->Write(scene_, log, scene.bytes());
}

void McapExport::Close() { w_->Close(); }

}  // namespace inhand::app
