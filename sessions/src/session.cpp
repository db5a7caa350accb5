#include "inhand/sessions/session.hpp"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/sessions/image_io.hpp"
#include "inhand/sessions/output_folder.hpp"
#include "session_format.hpp"

namespace fs = std::filesystem;

namespace inhand {

std::string FormatDouble(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

namespace {

// ---------------------------------------------------------------------------------------------
// CSV: comma-separated, one header line, no quoting (names and paths must not hold commas).

struct CsvRow {
  int line = 0;
  std::vector<std::string> fields;
};

struct Csv {
  std::string file;
  std::vector<std::string> header;
  long rows = 0;
};

// Into `out`, reusing its strings (no allocation per row once they have grown).
void SplitCsvLine(const std::string& line, std::vector<std::string>& out) {
  std::size_t start = 0, count = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    std::size_t end = comma == std::string::npos ? line.size() : comma;
    while (end > start && (line[end - 1] == ' ' || line[end - 1] == '\t')) --end;
    std::size_t lead = start;
    while (lead < end && (line[lead] == ' ' || line[lead] == '\t')) ++lead;
    if (out.size() <= count) out.emplace_back();
    out[count++].assign(line, lead, end - lead);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  out.resize(count);
}

// Streams the rows to `on_row(const Csv&, const CsvRow&)` as they are read: a session's joints
// are never held as text (a 10-minute recording at 500 Hz is 183 MB of it).
template <typename OnRow>
Csv ReadCsv(const std::string& path, OnRow&& on_row) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open (missing file?)");
  Csv csv;
  csv.file = path;
  std::string line;
  CsvRow row;
  int number = 0;
  bool have_header = false;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    if (!have_header) {
      SplitCsvLine(line, csv.header);
      have_header = true;
      std::set<std::string> seen;
      for (const std::string& h : csv.header)
        if (!seen.insert(h).second)
          throw InputError(path + ":" + std::to_string(number) + ": column '" + h +
                           "' appears twice");
      continue;
    }
    row.line = number;
    SplitCsvLine(line, row.fields);
    if (row.fields.size() != csv.header.size())
      throw InputError(path + ":" + std::to_string(number) + ": " +
                       std::to_string(row.fields.size()) + " columns, expected " +
                       std::to_string(csv.header.size()) + " as in the header");
    ++csv.rows;
    on_row(csv, row);
  }
  if (!have_header) throw InputError(path + ": empty file, expected a header line");
  return csv;
}

double ParseNumber(const Csv& csv, const CsvRow& row, std::size_t col) {
  const std::string& s = row.fields[col];
  double v = 0.0;
  const char* begin = s.data();
  const char* end = s.data() + s.size();
  if (!s.empty() && *begin == '+') ++begin;
  const auto res = std::from_chars(begin, end, v);
  if (s.empty() || res.ec != std::errc() || res.ptr != end || !std::isfinite(v))
    throw InputError(csv.file + ":" + std::to_string(row.line) + ": column '" + csv.header[col] +
                     "' is '" + s + "', expected a finite number");
  return v;
}

void RequireHeader(const Csv& csv, const std::vector<std::string>& expected) {
  if (csv.header != expected) {
    std::string e;
    for (const auto& h : expected) e += (e.empty() ? "" : ",") + h;
    throw InputError(csv.file + ":1: header must be '" + e + "'");
  }
}

// What a session's numbers can mean: a time within about 30 years of its origin (1e9 s; Unix
// times of today are 1.7e9 s: a recording's times start near 0, FORMAT.md), a position within
// 10 m of the palm. Beyond that a value is corrupt, and the filter's arithmetic would not stay
// finite with it.
constexpr double kMaxTime = 1e9;       // [s]
constexpr double kMaxDistance = 10.0;  // [m]

// Column 0 of a file's rows, read in order: a finite time that must increase from row to row.
class TimeColumn {
 public:
  double operator()(const Csv& csv, const CsvRow& row) {
    const double t = ParseNumber(csv, row, 0);
    if (!(std::abs(t) <= kMaxTime))
      throw InputError(csv.file + ":" + std::to_string(row.line) + ": time " + FormatDouble(t) +
                       " s, expected within +-1e9 s" + " (times count from the recording's start)");
    if (!(t > prev_))
      throw InputError(csv.file + ":" + std::to_string(row.line) + ": time " + FormatDouble(t) +
                       " does not increase (previous " + FormatDouble(prev_) + ")");
    prev_ = t;
    return t;
  }

 private:
  double prev_ = -std::numeric_limits<double>::infinity();
};

// px,py,pz,qw,qx,qy,qz starting at column `c`.
Transform ParsePose(const Csv& csv, const CsvRow& row, std::size_t c) {
  const Vec3 p(ParseNumber(csv, row, c), ParseNumber(csv, row, c + 1),
               ParseNumber(csv, row, c + 2));
  const Quat q(ParseNumber(csv, row, c + 3), ParseNumber(csv, row, c + 4),
               ParseNumber(csv, row, c + 5), ParseNumber(csv, row, c + 6));
  if (std::abs(q.norm() - 1.0) > 1e-3)
    throw InputError(csv.file + ":" + std::to_string(row.line) +
                     ": quaternion (qw, qx, qy, qz) has norm " + FormatDouble(q.norm()) +
                     ", expected 1 ± 1e-3");
  if (!(p.norm() <= kMaxDistance))
    throw InputError(csv.file + ":" + std::to_string(row.line) + ": position (px, py, pz) is " +
                     FormatDouble(p.norm()) + " m from the palm, expected within 10 m");
  return MakeTransform(p, q);
}

// A header: `leading` columns, then the pose's.
std::vector<std::string> WithPoseColumns(std::vector<std::string> leading) {
  leading.insert(leading.end(), kPoseColumns.begin(), kPoseColumns.end());
  return leading;
}

// session.json's "hand.joint_stiffness": one stiffness for every joint, or one per joint name
// ("*": the rest).
std::map<std::string, double> ReadJointStiffness(const jsonf::Field& ks) {
  std::map<std::string, double> out;
  if (ks.value.is_number()) {
    out["*"] = ks.PositiveNumber("N m/rad");
  } else if (ks.value.is_object() && !ks.value.empty()) {
    for (auto it = ks.value.begin(); it != ks.value.end(); ++it)
      out[it.key()] = ks[it.key()].PositiveNumber("N m/rad");
  } else {
    ks.Fail(
        "a stiffness > 0 in N m/rad for every joint, or an object {\"JOINT\": N m/rad, \"*\": "
        "for the rest}");
  }
  return out;
}

// session.json's "camera": the intrinsics, validated.
Intrinsics ReadIntrinsics(const jsonf::Field& c, const std::string& json_path) {
  Intrinsics K;
  K.width = c["width"].Integer();
  K.height = c["height"].Integer();
  K.fx = c["fx"].Number();
  K.fy = c["fy"].Number();
  K.cx = c["cx"].Number();
  K.cy = c["cy"].Number();
  if (c.Has("distortion")) {
    const jsonf::Field d = c["distortion"];
    if (d.Size() != 5) d.Fail("5 coefficients (k1, k2, p1, p2, k3)");
    for (std::size_t i = 0; i < 5; ++i) K.distortion[i] = d.At(i).Number();
  }
  K.Validate(json_path);
  return K;
}

}  // namespace

// -----------------------------------------------------------------------------------------------

std::string Session::Resolve(const std::string& relative) const {
  const fs::path p(relative);
  return p.is_absolute() ? p.string() : (fs::path(dir_) / p).lexically_normal().string();
}

Session Session::Load(const std::string& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir + ": session directory not found");
  Session s;
  s.dir_ = dir;
  const std::string json_path = (fs::path(dir) / "session.json").string();
  if (!fs::exists(json_path)) throw InputError(json_path + ": missing (every session has one)");
  s.info_ = ReadInfo(dir, json_path);
  s.LoadJoints();
  s.LoadCameraFrames(json_path);
  s.LoadGroundTruth();
  return s;
}

SessionInfo Session::ReadInfo(const std::string& dir, const std::string& json_path) {
  SessionInfo info;
  const jsonf::Json doc = jsonf::ReadFile(json_path);
  const jsonf::Field root{doc, json_path, ""};
  if (root["format"].String() != "inhand-session") root["format"].Fail("\"inhand-session\"");
  if (root["version"].Integer() != kSessionFormatVersion)
    root["version"].Fail("version " + std::to_string(kSessionFormatVersion) +
                         " (this build reads v1)");
  info.name = root.Has("name") ? root["name"].String() : fs::path(dir).filename().string();
  info.hand_urdf = root["hand"]["urdf"].String();
  if (root["hand"].Has("packages")) {
    const jsonf::Field pk = root["hand"]["packages"];
    if (!pk.value.is_object()) pk.Fail("an object {\"NAME\": \"DIR\"}");
    for (auto it = pk.value.begin(); it != pk.value.end(); ++it)
      info.packages[it.key()] = pk[it.key()].String();
  }
  if (root["hand"].Has("joint_stiffness"))
    info.joint_stiffness = ReadJointStiffness(root["hand"]["joint_stiffness"]);
  info.object = root["object"]["model"].String();
  if (root.Has("conventions")) {
    const jsonf::Field c = root["conventions"];
    if (c.Has("quaternion") && c["quaternion"].String() != "wxyz") c["quaternion"].Fail("\"wxyz\"");
    if (c.Has("torque") && c["torque"].String() != "external")
      c["torque"].Fail("\"external\" (joint torques of contact forces only, see FORMAT.md)");
    if (c.Has("length") && c["length"].String() != "m") c["length"].Fail("\"m\"");
    if (c.Has("angle") && c["angle"].String() != "rad") c["angle"].Fail("\"rad\"");
  }
  if (root.Has("camera") && !root["camera"].value.is_null())
    info.camera = ReadIntrinsics(root["camera"], json_path);
  const jsonf::Field init = root["initial_estimate"];
  info.initial_T_PO = init["T_PO"].Pose();
  if (!(info.initial_T_PO.translation().norm() <= kMaxDistance))
    init["T_PO"]["xyz"].Fail("a position within 10 m of the palm");
  // The ranges that keep the filter's arithmetic finite (StartSigmas::Validate).
  const auto within = [](const jsonf::Field& f, double lo, double hi, const char* expected) {
    const double v = f.Number();
    if (!(v >= lo && v <= hi)) f.Fail(expected);
    return v;
  };
  info.sigma_position = within(init["sigma_position"], 1e-6, 10.0, "a number in [1e-6, 10] m");
  info.sigma_orientation =
      within(init["sigma_orientation"], 1e-6, 2 * M_PI, "a number in [1e-6, 2 pi] rad");
  info.sigma_joint_bias =
      within(init["sigma_joint_bias"], 0.0, 2 * M_PI, "a number in [0, 2 pi] rad");
  if (root.Has("provenance")) info.provenance_json = root["provenance"].value.dump();
  return info;
}

// joints.csv: t, q:<joint>..., then tau:<joint>... for the same joints or no torque columns at
// all (hands without torque sensors). Parsed row by row into flat buffers.
void Session::LoadJoints() {
  std::size_t m = 0, m_tau = 0;
  std::vector<double> q_rows, tau_rows;
  TimeColumn joint_time;
  const Csv joints =
      ReadCsv((fs::path(dir_) / "joints.csv").string(), [&](const Csv& csv, const CsvRow& row) {
        if (m == 0) {  // the header, checked at the first row
          if (csv.header.empty() || csv.header[0] != "t")
            throw InputError(csv.file + ":1: first column must be 't'");
          while (1 + m < csv.header.size() && csv.header[1 + m].rfind("q:", 0) == 0) ++m;
          const std::size_t rest = csv.header.size() - 1 - m;
          if (m == 0 || (rest != 0 && rest != m))
            throw InputError(csv.file +
                             ":1: expected t, then q:NAME for every joint, then tau:NAME for "
                             "every joint or no torque columns (got " +
                             std::to_string(m) + " q: and " + std::to_string(rest) +
                             " other columns after t)");
          m_tau = rest;
          for (std::size_t j = 0; j < m; ++j) {
            const std::string& qh = csv.header[1 + j];
            if (qh.size() < 3)
              throw InputError(csv.file + ":1: column " + std::to_string(2 + j) + " is '" + qh +
                               "', expected q:NAME");
            const std::string name = qh.substr(2);
            if (m_tau > 0) {
              const std::string& th = csv.header[1 + m + j];
              if (th != "tau:" + name)
                throw InputError(csv.file + ":1: column " + std::to_string(2 + m + j) + " is '" +
                                 th + "', expected 'tau:" + name +
                                 "' (torques in the order of the positions)");
            }
            joint_names_.push_back(name);
          }
        }
        t_.push_back(joint_time(csv, row));
        for (std::size_t j = 0; j < m; ++j) q_rows.push_back(ParseNumber(csv, row, 1 + j));
        for (std::size_t j = 0; j < m_tau; ++j)
          tau_rows.push_back(ParseNumber(csv, row, 1 + m + j));
      });
  if (joints.rows == 0) throw InputError(joints.file + ": no samples");
  const long n = joints.rows;
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  q_ = Eigen::Map<const RowMajor>(q_rows.data(), n, static_cast<long>(m));
  std::vector<double>().swap(q_rows);
  tau_ = Eigen::Map<const RowMajor>(tau_rows.data(), n, static_cast<long>(m_tau));
  std::vector<double>().swap(tau_rows);
  t_.shrink_to_fit();
}

// camera.csv: t, image, pose of the camera in P; present exactly when session.json has a camera.
void Session::LoadCameraFrames(const std::string& json_path) {
  const fs::path camera_csv = fs::path(dir_) / "camera.csv";
  if (info_.camera && !fs::exists(camera_csv))
    throw InputError(camera_csv.string() + ": missing, but session.json declares a camera");
  if (fs::exists(camera_csv)) {
    if (!info_.camera)
      throw InputError(json_path +
                       ": camera.csv exists but session.json has no \"camera\" intrinsics");
    TimeColumn frame_time;
    const Csv cam_file = ReadCsv(camera_csv.string(), [&](const Csv& cam, const CsvRow& row) {
      if (frames_.empty()) RequireHeader(cam, WithPoseColumns({"t", "image"}));
      CameraFrame f;
      f.t = frame_time(cam, row);
      f.image = row.fields[1];
      if (f.image.empty() || !fs::is_regular_file(Resolve(f.image)))
        throw InputError(cam.file + ":" + std::to_string(row.line) + ": image '" + f.image +
                         "' not found in the session");
      f.T_PC = ParsePose(cam, row, 2);
      frames_.push_back(f);
    });
    RequireHeader(cam_file, WithPoseColumns({"t", "image"}));
  }
}

// groundtruth.csv (optional): t, pose of the object in P.
void Session::LoadGroundTruth() {
  const fs::path gt_csv = fs::path(dir_) / "groundtruth.csv";
  if (fs::exists(gt_csv)) {
    TimeColumn sample_time;
    const Csv gt_file = ReadCsv(gt_csv.string(), [&](const Csv& gt, const CsvRow& row) {
      if (groundtruth_.empty()) RequireHeader(gt, WithPoseColumns({"t"}));
      GroundTruthSample g;
      g.t = sample_time(gt, row);
      g.T_PO = ParsePose(gt, row, 1);
      groundtruth_.push_back(g);
    });
    RequireHeader(gt_file, WithPoseColumns({"t"}));
  }
}

Image8 Session::LoadImage(int i) const {
  INHAND_CHECK(i >= 0 && i < static_cast<int>(frames_.size()), "camera frame index out of range");
  const std::string path = Resolve(frames_[static_cast<std::size_t>(i)].image);
  Image8 image = ReadImage(path);
  const Intrinsics& K = *info_.camera;
  if (image.width != K.width || image.height != K.height)
    throw InputError(path + ": image is " + std::to_string(image.width) + "x" +
                     std::to_string(image.height) + ", session.json's camera says " +
                     std::to_string(K.width) + "x" + std::to_string(K.height));
  return image;
}

Transform Session::GroundTruthAt(double t) const {
  INHAND_CHECK(!groundtruth_.empty(), "session has no ground truth");
  if (t <= groundtruth_.front().t) return groundtruth_.front().T_PO;
  if (t >= groundtruth_.back().t) return groundtruth_.back().T_PO;
  const auto it = std::upper_bound(groundtruth_.begin(), groundtruth_.end(), t,
                                   [](double v, const GroundTruthSample& g) { return v < g.t; });
  const GroundTruthSample& b = *it;
  const GroundTruthSample& a = *(it - 1);
  const double w = (t - a.t) / (b.t - a.t);
  const Quat qa(a.T_PO.linear()), qb(b.T_PO.linear());
  return MakeTransform((1.0 - w) * a.T_PO.translation() + w * b.T_PO.translation(),
                       qa.slerp(w, qb));
}

std::vector<int> Session::JointColumns(const HandModel& hand) const {
  const std::vector<std::string> names = hand.QNames();
  std::vector<int> column(names.size(), -1);
  for (std::size_t c = 0; c < joint_names_.size(); ++c) {
    const auto it = std::find(names.begin(), names.end(), joint_names_[c]);
    if (it == names.end())
      throw InputError(Resolve("joints.csv") + ":1: joint '" + joint_names_[c] +
                       "' is not a moving, independent joint of " + hand.source);
    column[static_cast<std::size_t>(it - names.begin())] = static_cast<int>(c);
  }
  for (std::size_t j = 0; j < names.size(); ++j)
    if (column[j] < 0)
      throw InputError(Resolve("joints.csv") + ":1: no column for joint '" + names[j] + "' of " +
                       hand.source + " (" + std::to_string(names.size()) + " joints expected)");
  return column;
}

std::vector<Session::LimitViolation> Session::LimitViolations(
    const HandModel& hand, const std::vector<int>& columns) const {
  std::vector<LimitViolation> out;
  for (int i = 0; i < hand.num_q(); ++i) {
    const Joint& joint = hand.QJoint(i);
    if (!joint.has_limits) continue;
    LimitViolation v;
    v.q_index = i;
    v.joint = joint.name;
    double worst_by = 0.0;
    const auto column = q_.col(columns[static_cast<std::size_t>(i)]);
    for (Eigen::Index k = 0; k < column.size(); ++k) {
      const double x = column[k];
      if (!std::isfinite(x)) continue;  // the player reports those
      const double by =
          x < joint.lower ? joint.lower - x : (x > joint.upper ? x - joint.upper : 0.0);
      if (!(by > 0.0)) continue;
      ++(x < joint.lower ? v.below : v.above);
      if (by > worst_by) {
        worst_by = by;
        v.worst = x;
        v.limit = x < joint.lower ? joint.lower : joint.upper;
      }
    }
    if (v.below + v.above > 0) out.push_back(v);
  }
  return out;
}

std::vector<std::string> Session::LimitWarnings(const HandModel& hand,
                                                const std::vector<int>& columns) const {
  std::vector<std::string> out;
  for (const LimitViolation& v : LimitViolations(hand, columns)) {
    if (std::abs(v.worst - v.limit) <= info_.sigma_joint_bias)
      continue;  // what the encoders may be off by
    std::ostringstream line;
    line << Resolve("joints.csv") << ": q:" << v.joint << " beyond its ";
    if (v.below > 0 && v.above > 0)
      line << "limits in " << v.below << " (below) and " << v.above << " (above)";
    else
      line << (v.below > 0 ? "lower" : "upper") << " limit " << v.limit << " in "
           << v.below + v.above;
    line << " of " << num_samples() << " samples (worst " << v.worst << ", by "
         << std::abs(v.worst - v.limit) << ")";
    out.push_back(line.str());
  }
  return out;
}

SessionModels LoadSessionModels(const Session& session, bool load_visual_meshes) {
  PackageMap packages;
  for (const auto& [name, d] : session.info().packages) {
    const std::string resolved = session.Resolve(d);
    if (!fs::is_directory(resolved))
      throw InputError(session.Resolve("session.json") + ": package '" + name + "' maps to '" + d +
                       "', which is not a directory");
    packages.dirs[name] = resolved;
  }
  HandLoadOptions options;
  options.packages = packages;
  options.load_visual_meshes = load_visual_meshes;
  SessionModels models{LoadHandModel(session.Resolve(session.info().hand_urdf), options),
                       LoadObjectModel(session.Resolve(session.info().object), packages),
                       {}};
  models.joint_columns = session.JointColumns(models.hand);
  const std::map<std::string, double>& ks = session.info().joint_stiffness;
  if (!ks.empty()) {
    const std::vector<std::string> names = models.hand.QNames();
    for (const auto& [name, k] : ks)
      if (name != "*" && std::find(names.begin(), names.end(), name) == names.end())
        throw InputError(session.Resolve("session.json") + ": field 'hand.joint_stiffness." + name +
                         "': the hand has no independent joint of that name");
    const auto all = ks.find("*");
    models.hand.joint_stiffness.assign(names.size(), all != ks.end() ? all->second : 0.0);
    for (std::size_t j = 0; j < names.size(); ++j) {
      const auto it = ks.find(names[j]);
      if (it != ks.end()) models.hand.joint_stiffness[j] = it->second;
    }
  }
  return models;
}

}  // namespace inhand
