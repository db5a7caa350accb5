#pragma once
// Session format v1 (sessions/FORMAT.md is the normative text): a directory with session.json,
// joints.csv, camera.csv + images/, and optionally groundtruth.csv. Reading validates
// everything up front and throws InputError naming the file, line and column at fault.
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "inhand/core/hand_model.hpp"
#include "inhand/core/image.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/core/object_model.hpp"

namespace inhand {

struct SessionInfo {
  std::string name;
  // Paths as written in session.json (relative ones are relative to the session directory).
  std::string hand_urdf;
  std::map<std::string, std::string> packages;  // package name → directory
  std::string object;                           // object description (.json or .urdf)
  // hand.joint_stiffness [N m/rad]: by joint name, or under "*" one value for every joint.
  std::map<std::string, double> joint_stiffness;
  std::optional<Intrinsics> camera;  // absent: no images
  Transform initial_T_PO = Transform::Identity();
  double sigma_position = 0.020;                // [m]   initial σ of the object position
  double sigma_orientation = 5.0 * M_PI / 180;  // [rad] initial σ of the object orientation
  double sigma_joint_bias = 5.0 * M_PI / 180;   // [rad] initial σ of each joint bias
  // Free-form provenance (simulator, scenario, seed, noise profile, ...), kept as JSON text.
  std::string provenance_json = "{}";
};

struct CameraFrame {
  double t = 0.0;     // [s]
  std::string image;  // relative to the session directory
  Transform T_PC;     // camera pose in the palm frame at t
};

struct GroundTruthSample {
  double t = 0.0;
  Transform T_PO;
};

class Session {
 public:
  // Reads and validates a session directory. Throws InputError.
  static Session Load(const std::string& dir);

  const std::string& dir() const { return dir_; }
  const SessionInfo& info() const { return info_; }
  std::string Resolve(const std::string& relative) const;  // path inside the session

  // Joint samples, in the order of joint_names() (the file's column order).
  const std::vector<std::string>& joint_names() const { return joint_names_; }
  int num_samples() const { return static_cast<int>(t_.size()); }
  double t(int k) const { return t_[k]; }
  const std::vector<double>& times() const { return t_; }
  Eigen::Ref<const Eigen::VectorXd> q(int k) const { return q_.row(k).transpose(); }
  // Joint torques, when joints.csv has tau: columns (hands without torque sensors have none).
  bool has_torques() const { return tau_.cols() > 0; }
  Eigen::Ref<const Eigen::VectorXd> tau(int k) const { return tau_.row(k).transpose(); }
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& q_all() const {
    return q_;
  }
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& tau_all() const {
    return tau_;
  }

  const std::vector<CameraFrame>& camera_frames() const { return frames_; }
  // Decodes frame i's image (RGB). Throws InputError when unreadable or of the wrong size.
  Image8 LoadImage(int i) const;

  bool has_groundtruth() const { return !groundtruth_.empty(); }
  const std::vector<GroundTruthSample>& groundtruth() const { return groundtruth_; }
  // Ground truth at time t: linear in position, slerp in orientation; clamps at the ends.
  Transform GroundTruthAt(double t) const;

  // For each of `hand`'s configuration entries (HandModel::QNames order), its column among
  // joint_names(). Throws InputError when a column names a joint the URDF does not have, or a
  // joint of the hand has no column. The session itself stays as it was read.
  std::vector<int> JointColumns(const HandModel& hand) const;

  // Joint samples beyond the URDF's limits, one entry per joint that has any (configuration
  // order): how many below / above, the worst value and the limit it passes. Real hands' encoders
  // overshoot their URDFs (19 of 20 recorded Allegro grasps pass joint_12.0's upper limit).
  struct LimitViolation {
    int q_index = -1;
    std::string joint;
    long below = 0, above = 0;  // samples
    double worst = 0.0;         // the sample farthest beyond its limit
    double limit = 0.0;         // the limit it passes
  };
  std::vector<LimitViolation> LimitViolations(const HandModel& hand,
                                              const std::vector<int>& columns) const;
  // One warning line per such joint: "DIR/joints.csv: q:NAME beyond its upper limit L in N of M
  // samples (worst W, by D)", for the joints whose worst sample passes its limit by more than
  // the session's declared joint-bias σ (sigma_joint_bias): an encoder that is off by that much
  // reads beyond the limit when its joint rests on it (the simulator's index_flex2, 2.2° below 0
  // in the demo session), which says nothing about the recording.
  std::vector<std::string> LimitWarnings(const HandModel& hand,
                                         const std::vector<int>& columns) const;

 private:
  // Load's steps: session.json, then joints.csv, camera.csv and groundtruth.csv beside it.
  static SessionInfo ReadInfo(const std::string& dir, const std::string& json_path);
  void LoadJoints();
  void LoadCameraFrames(const std::string& json_path);
  void LoadGroundTruth();

  std::string dir_;
  SessionInfo info_;
  std::vector<std::string> joint_names_;
  std::vector<double> t_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> q_, tau_;
  std::vector<CameraFrame> frames_;
  std::vector<GroundTruthSample> groundtruth_;
};

// The hand and object a session refers to, loaded through io/ with the session's package map,
// and the session's joint columns matched to the hand. The hand carries the session's joint
// stiffness (HandModel::joint_stiffness).
struct SessionModels {
  HandModel hand;
  ObjectModel object;
  std::vector<int> joint_columns;  // Session::JointColumns(hand)
};
SessionModels LoadSessionModels(const Session& session, bool load_visual_meshes = true);

// Writes a session into a temporary directory beside `dir` and renames it into place on
// Commit(), so a failed run never leaves a half-written session. Destroying an uncommitted
// writer removes the temporary directory.
class SessionWriter {
 public:
  // `torques` false: joints.csv gets no tau: columns, and AddJointSample takes an empty tau.
  SessionWriter(std::string dir, SessionInfo info, std::vector<std::string> joint_names,
                bool overwrite = false, bool torques = true);
  ~SessionWriter();
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;

  void AddJointSample(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& tau);
  // Writes images/frame_NNNNNN.png at once.
  void AddCameraFrame(double t, const Image8& image, const Transform& T_PC);
  // Moves an image file already written (png or jpg, on the same file system: an importer
  // encodes frames while it reads) to images/frame_NNNNNN.EXT; the caller has checked that it
  // decodes to an image of the intrinsics' size. The pose as translation + quaternion, written
  // digit for digit (an importer passes recorded poses on).
  void AdoptCameraFrame(double t, const std::string& file, const std::string& extension,
                        const Vec3& p_PC, const Quat& q_PC);
  void AddGroundTruth(double t, const Transform& T_PO);
  void AddGroundTruth(double t, const Vec3& p_PO, const Quat& q_PO);
  // Any extra file (e.g. the simulator's true biases), relative to the session directory.
  void AddFile(const std::string& relative_path, const std::string& contents);
  void Commit();

  const std::string& temp_dir() const { return tmp_; }

 private:
  std::string dir_, tmp_;
  std::filesystem::path final_;
  SessionInfo info_;
  std::vector<std::string> joint_names_;
  bool overwrite_;
  bool torques_;
  bool committed_ = false;
  std::string joints_csv_, camera_csv_, groundtruth_csv_;
  int num_frames_ = 0;
  double last_joint_t_ = -std::numeric_limits<double>::infinity();
};

// Shortest decimal text that reads back to the same double (std::to_chars).
std::string FormatDouble(double v);

}  // namespace inhand
