#include "inhand/sessions/session.hpp"

#include <filesystem>
#include <fstream>

#include "inhand/core/error.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/sessions/image_io.hpp"
#include "inhand/sessions/output_folder.hpp"
#include "session_format.hpp"

namespace fs = std::filesystem;

namespace inhand {
namespace {

std::string PoseFields(const Vec3& p, const Quat& q) {
  std::string s;
  for (double v : {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()}) s += "," + FormatDouble(v);
  return s;
}
std::string PoseFields(const Transform& T) { return PoseFields(T.translation(), Quat(T.linear())); }

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InputError(path.string() + ": cannot write");
  out << text;
  if (!out) throw InputError(path.string() + ": write failed");
}

}  // namespace

SessionWriter::SessionWriter(std::string dir, SessionInfo info,
                             std::vector<std::string> joint_names, bool overwrite, bool torques)
    : dir_(std::move(dir)),
      info_(std::move(info)),
      joint_names_(std::move(joint_names)),
      overwrite_(overwrite),
      torques_(torques) {
  if (joint_names_.empty()) throw InputError("session writer: no joints");
  if (fs::exists(fs::absolute(dir_)) && !overwrite_)
    throw InputError(dir_ + ": already exists (pass overwrite to replace it)");
  final_ = CheckOutputFolder(dir_);
  tmp_ = PrepareStaging(final_).string();
  std::error_code ec;
  fs::create_directories(fs::path(tmp_) / "images", ec);
  if (ec) throw InputError(tmp_ + ": cannot create (" + ec.message() + ")");
  joints_csv_ = "t";
  for (const auto& n : joint_names_) joints_csv_ += ",q:" + n;
  if (torques_)
    for (const auto& n : joint_names_) joints_csv_ += ",tau:" + n;
  joints_csv_ += "\n";
  camera_csv_ = "t,image";
  groundtruth_csv_ = "t";
  for (const auto& c : kPoseColumns) camera_csv_ += "," + c, groundtruth_csv_ += "," + c;
  camera_csv_ += "\n";
  groundtruth_csv_ += "\n";
}

SessionWriter::~SessionWriter() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(tmp_, ec);
  }
}

void SessionWriter::AddJointSample(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                                   const Eigen::Ref<const Eigen::VectorXd>& tau) {
  INHAND_CHECK(
      q.size() == static_cast<long>(joint_names_.size()) && tau.size() == (torques_ ? q.size() : 0),
      "joint sample size does not match the joint names (or torques given to a torque-free "
      "session)");
  INHAND_CHECK(t > last_joint_t_, "joint samples must be added in increasing time");
  last_joint_t_ = t;
  joints_csv_ += FormatDouble(t);
  for (long j = 0; j < q.size(); ++j) joints_csv_ += "," + FormatDouble(q[j]);
  for (long j = 0; j < tau.size(); ++j) joints_csv_ += "," + FormatDouble(tau[j]);
  joints_csv_ += "\n";
}

void SessionWriter::AddCameraFrame(double t, const Image8& image, const Transform& T_PC) {
  INHAND_CHECK(info_.camera.has_value(), "camera frames need camera intrinsics in SessionInfo");
  INHAND_CHECK(image.width == info_.camera->width && image.height == info_.camera->height &&
                   image.channels == 3,
               "camera frame must be RGB of the intrinsics' size");
  char name[64];
  std::snprintf(name, sizeof(name), "images/frame_%06d.png", num_frames_++);
  WriteImage((fs::path(tmp_) / name).string(), image);
  camera_csv_ += FormatDouble(t) + "," + name + PoseFields(T_PC) + "\n";
}

void SessionWriter::AdoptCameraFrame(double t, const std::string& file,
                                     const std::string& extension, const Vec3& p_PC,
                                     const Quat& q_PC) {
  INHAND_CHECK(info_.camera.has_value(), "camera frames need camera intrinsics in SessionInfo");
  INHAND_CHECK(extension == "png" || extension == "jpg", "adopted frames are png or jpg");
  char name[64];
  std::snprintf(name, sizeof(name), "images/frame_%06d.%s", num_frames_++, extension.c_str());
  std::error_code ec;
  fs::rename(file, fs::path(tmp_) / name, ec);
  if (ec) throw InputError(file + ": cannot move into " + tmp_ + " (" + ec.message() + ")");
  camera_csv_ += FormatDouble(t) + "," + name + PoseFields(p_PC, q_PC) + "\n";
}

void SessionWriter::AddGroundTruth(double t, const Transform& T_PO) {
  groundtruth_csv_ += FormatDouble(t) + PoseFields(T_PO) + "\n";
}

void SessionWriter::AddGroundTruth(double t, const Vec3& p_PO, const Quat& q_PO) {
  groundtruth_csv_ += FormatDouble(t) + PoseFields(p_PO, q_PO) + "\n";
}

void SessionWriter::AddFile(const std::string& relative_path, const std::string& contents) {
  const fs::path p = fs::path(tmp_) / relative_path;
  fs::create_directories(p.parent_path());
  WriteText(p, contents);
}

void SessionWriter::Commit() {
  INHAND_CHECK(!committed_, "session already committed");
  jsonf::Json doc = {
      {"format", "inhand-session"},
      {"version", kSessionFormatVersion},
      {"name", info_.name},
      {"hand", {{"urdf", info_.hand_urdf}}},
      {"object", {{"model", info_.object}}},
      {"conventions",
       {{"quaternion", "wxyz"}, {"torque", "external"}, {"length", "m"}, {"angle", "rad"}}},
      {"initial_estimate",
       {{"T_PO", jsonf::PoseToJson(info_.initial_T_PO)},
        {"sigma_position", info_.sigma_position},
        {"sigma_orientation", info_.sigma_orientation},
        {"sigma_joint_bias", info_.sigma_joint_bias}}},
      {"provenance", jsonf::Json::parse(info_.provenance_json)}};
  if (!info_.packages.empty()) doc["hand"]["packages"] = info_.packages;
  if (info_.joint_stiffness.size() == 1 && info_.joint_stiffness.count("*"))
    doc["hand"]["joint_stiffness"] = info_.joint_stiffness.at("*");
  else if (!info_.joint_stiffness.empty())
    doc["hand"]["joint_stiffness"] = info_.joint_stiffness;
  if (info_.camera) {
    const Intrinsics& K = *info_.camera;
    doc["camera"] = {
        {"width", K.width},
        {"height", K.height},
        {"fx", K.fx},
        {"fy", K.fy},
        {"cx", K.cx},
        {"cy", K.cy},
        {"distortion",
         {K.distortion[0], K.distortion[1], K.distortion[2], K.distortion[3], K.distortion[4]}}};
  }
  WriteText(fs::path(tmp_) / "session.json", doc.dump(2) + "\n");
  WriteText(fs::path(tmp_) / "joints.csv", joints_csv_);
  if (info_.camera) WriteText(fs::path(tmp_) / "camera.csv", camera_csv_);
  if (groundtruth_csv_.find('\n') + 1 < groundtruth_csv_.size())
    WriteText(fs::path(tmp_) / "groundtruth.csv", groundtruth_csv_);
  if (num_frames_ == 0) fs::remove(fs::path(tmp_) / "images");
  if (fs::exists(final_) && !overwrite_)
    throw InputError(dir_ + ": appeared while writing; not replaced");
  CommitStaging(tmp_, final_, "(session)");
  committed_ = true;
}

}  // namespace inhand
