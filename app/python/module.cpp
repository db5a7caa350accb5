// The Python module `inhand` (pybind11): sessions, the hand and object models, and the online
// Tracker, with NumPy arrays in and out. Poses are 4×4 arrays (T_AB: frame B in A), images
// H×W×3 (RGB) or H×W (grey) uint8 arrays. Errors raise inhand.InputError (a ValueError) with the
// C++ message. Every call that can take longer than a millisecond releases the GIL.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <unistd.h>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "inhand/app/commands.hpp"
#include "inhand/app/modalities.hpp"
#include "inhand/core/error.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/sessions/install_dirs.hpp"
#include "inhand/sessions/session.hpp"
#include "inhand/tracker/tracker.hpp"

namespace py = pybind11;

namespace inhand {
namespace {

using Mat4 = Eigen::Matrix4d;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// A 4×4 rigid transform from Python: finite, last row (0 0 0 1), rotation orthonormal with
// determinant 1 (within 1e-6).
Transform ToTransform(const Mat4& m, const char* what) {
  if (!m.allFinite()) throw InputError(std::string(what) + ": not finite");
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 0.0)
    throw InputError(std::string(what) + ": last row is not (0 0 0 1)");
  const Mat3 R = m.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      std::abs(R.determinant() - 1.0) > 1e-6)
    throw InputError(std::string(what) + ": the top-left 3x3 block is not a rotation");
  Transform T = Transform::Identity();
  T.linear() = R;
  T.translation() = m.topRightCorner<3, 1>();
  return T;
}

// Tracker parameters: None (the defaults), a dict (as the JSON file) or JSON text.
TrackerParams ParamsFrom(const py::object& params) {
  if (params.is_none()) return TrackerParams();
  if (py::isinstance<py::str>(params))
    return TrackerParamsFromJson(params.cast<std::string>(), "tracker parameters");
  if (py::isinstance<py::dict>(params))
    return TrackerParamsFromJson(
        py::module_::import("json").attr("dumps")(params).cast<std::string>(),
        "tracker parameters");
  throw InputError("tracker parameters: expected None, a dict or JSON text");
}

Intrinsics IntrinsicsFrom(const Mat3& K, int width, int height,
                          const std::vector<double>& distortion) {
  Intrinsics in;
  in.width = width;
  in.height = height;
  in.fx = K(0, 0);
  in.fy = K(1, 1);
  in.cx = K(0, 2);
  in.cy = K(1, 2);
  if (K(0, 1) != 0.0 || K(1, 0) != 0.0 || K(2, 0) != 0.0 || K(2, 1) != 0.0 || K(2, 2) != 1.0)
    throw InputError("K: expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]");
  if (!distortion.empty()) {
    if (distortion.size() != 5)
      throw InputError("distortion: expected 5 values (k1 k2 p1 p2 k3), got " +
                       std::to_string(distortion.size()));
    std::copy(distortion.begin(), distortion.end(), in.distortion.begin());
  }
  in.Validate("K");
  return in;
}

Mat3 KOf(const Intrinsics& in) {
  Mat3 K;
  K << in.fx, 0.0, in.cx, 0.0, in.fy, in.cy, 0.0, 0.0, 1.0;
  return K;
}

Image8 ImageFrom(const py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>& a) {
  if (a.ndim() != 2 && !(a.ndim() == 3 && (a.shape(2) == 3 || a.shape(2) == 1)))
    throw InputError("image: expected an H x W x 3 (RGB) or H x W (grey) uint8 array");
  Image8 image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)),
               a.ndim() == 3 ? static_cast<int>(a.shape(2)) : 1);
  std::memcpy(image.data.data(), a.data(), image.data.size());
  return image;
}

py::array_t<std::uint8_t> ToArray(const Image8& image) {
  std::vector<py::ssize_t> shape = {image.height, image.width};
  if (image.channels > 1) shape.push_back(image.channels);
  py::array_t<std::uint8_t> a(shape);
  std::memcpy(a.mutable_data(), image.data.data(), image.data.size());
  return a;
}

py::dict HealthDict(const Health& h, const HandModel& hand) {
  py::dict d;
  d["state"] = HealthStateName(h.state);
  d["cause"] = HealthCauseName(h.cause);
  d["value"] = h.value;
  d["subject"] = h.subject;
  d["since"] = h.since;
  d["message"] = HealthMessage(h, hand);
  return d;
}

py::dict StatsDict(const TrackerStats& s) {
  py::dict d;
  d["samples"] = s.samples;
  d["samples_dropped"] = s.samples_dropped;
  d["samples_rejected"] = s.samples_rejected;
  d["images_added"] = s.images_added;
  d["images_fused"] = s.images_fused;
  d["images_dropped_late"] = s.images_dropped_late;
  d["images_dropped_busy"] = s.images_dropped_busy;
  d["images_rejected"] = s.images_rejected;
  d["rewinds"] = s.rewinds;
  d["samples_replayed"] = s.samples_replayed;
  d["relocalizations"] = s.relocalizations;
  d["images_features_lost"] = s.images_features_lost;
  d["images_tags_elsewhere"] = s.images_tags_elsewhere;
  d["recoveries"] = s.recoveries;
  d["shifts_refused"] = s.shifts_refused;
  return d;
}

// A tracker parameter file for the commands (they read a file, as their --params): None → "",
// os.PathLike → that file, a dict or JSON text → validated, then written to a temporary file
// removed when this goes out of scope.
class ParamsFile {
 public:
  explicit ParamsFile(const py::object& params) {
    if (params.is_none()) return;
    if (py::isinstance(params, py::module_::import("os").attr("PathLike"))) {
      path_ = py::str(py::module_::import("os").attr("fspath")(params)).cast<std::string>();
      return;
    }
    const TrackerParams p = ParamsFrom(params);
    static std::atomic<int> counter{0};
    temp_ =
        std::filesystem::temp_directory_path() /
        ("inhand-params-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".json");
    std::ofstream(temp_) << TrackerParamsToJson(p) << "\n";
    path_ = temp_.string();
  }
  ~ParamsFile() {
    std::error_code ec;
    if (!temp_.empty()) std::filesystem::remove(temp_, ec);
  }
  ParamsFile(const ParamsFile&) = delete;
  ParamsFile& operator=(const ParamsFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::filesystem::path temp_;
};

py::object JsonFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot read");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return py::module_::import("json").attr("loads")(text);
}

py::dict SimulationDict(const SimulationSummary& s) {
  py::dict d;
  d["session_dir"] = s.session_dir;
  d["duration"] = s.duration;
  d["wall_time"] = s.wall_time;
  d["joint_samples"] = s.joint_samples;
  d["camera_frames"] = s.camera_frames;
  d["max_penetration"] = s.max_penetration;
  d["held_fraction"] = s.held_fraction;
  d["tilt_in_hand_deg"] = s.tilt_in_hand_deg;
  d["max_in_hand_rotation_deg"] = s.max_in_hand_rotation_deg;
  d["table_travel_before_grasp"] = s.table_travel_before_grasp;
  d["lift_height"] = s.lift_height;
  return d;
}

// The `inhand` command evaluate runs its runs with: given, or beside the module (the build
// tree's bin/ next to python/; an installation's PREFIX/bin from PREFIX/lib/python3.X/
// dist-packages), or on PATH.
std::string InhandBinary(const std::string& given) {
  namespace fs = std::filesystem;
  if (!given.empty()) {
    if (!fs::is_regular_file(given)) throw InputError("inhand_binary: " + given + ": no such file");
    return fs::absolute(given).string();
  }
  for (const fs::path& p : BesideRunningCode("bin/inhand"))
    if (fs::is_regular_file(p)) return fs::canonical(p).string();
  const py::object which = py::module_::import("shutil").attr("which")("inhand");
  if (!which.is_none()) return which.cast<std::string>();
  throw InputError(
      "evaluate: cannot find the inhand command (beside the module or on PATH); pass "
      "inhand_binary=");
}

// Writes a session from Python, checking what the C++ writer takes as programming errors.
class PySessionWriter {
 public:
  PySessionWriter(const std::string& dir, const std::string& hand_urdf, const std::string& object,
                  const std::vector<std::string>& joint_names, bool torques,
                  const std::optional<Mat3>& K, const std::optional<std::pair<int, int>>& size,
                  const std::vector<double>& distortion, const Mat4& initial_pose,
                  double sigma_position, double sigma_orientation, double sigma_joint_bias,
                  const std::map<std::string, std::string>& packages,
                  const std::map<std::string, double>& joint_stiffness, const std::string& name,
                  const py::object& provenance, bool overwrite)
      : num_joints_(static_cast<long>(joint_names.size())), torques_(torques) {
    SessionInfo info;
    info.name = name.empty() ? std::filesystem::path(dir).filename().string() : name;
    if (hand_urdf.empty() || object.empty())
      throw InputError("SessionWriter: hand_urdf and object are required");
    info.hand_urdf = hand_urdf;
    info.object = object;
    info.packages = packages;
    for (const auto& [joint, k] : joint_stiffness)
      if (!(k > 0.0) || !std::isfinite(k))
        throw InputError("joint_stiffness: " + joint + ": expected a positive stiffness");
    info.joint_stiffness = joint_stiffness;
    if (K.has_value() != size.has_value())
      throw InputError("SessionWriter: give K and image_size (width, height) together");
    if (K) info.camera = IntrinsicsFrom(*K, size->first, size->second, distortion);
    info.initial_T_PO = ToTransform(initial_pose, "initial_pose");
    for (const double sigma : {sigma_position, sigma_orientation, sigma_joint_bias})
      if (!(sigma > 0.0) || !std::isfinite(sigma))
        throw InputError("SessionWriter: the sigmas must be positive");
    info.sigma_position = sigma_position;
    info.sigma_orientation = sigma_orientation;
    info.sigma_joint_bias = sigma_joint_bias;
    if (!provenance.is_none()) {
      if (!py::isinstance<py::dict>(provenance))
        throw InputError("provenance: expected a dict (kept as JSON)");
      info.provenance_json =
          py::module_::import("json").attr("dumps")(provenance).cast<std::string>();
    }
    camera_ = info.camera.has_value();
    if (camera_) width_ = info.camera->width, height_ = info.camera->height;
    writer_ =
        std::make_unique<SessionWriter>(dir, std::move(info), joint_names, overwrite, torques);
  }

  void AddJointSample(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const std::optional<Eigen::Ref<const Eigen::VectorXd>>& tau) {
    Writable();
    if (!std::isfinite(t) || !(t > last_t_))
      throw InputError("add_joint_sample: t = " + FormatDouble(t) +
                       ": expected finite and after the previous sample's " +
                       FormatDouble(last_t_));
    if (q.size() != num_joints_ || !q.allFinite())
      throw InputError("q: expected " + std::to_string(num_joints_) + " finite values, got " +
                       std::to_string(q.size()));
    if (torques_ && (!tau || tau->size() != num_joints_ || !tau->allFinite()))
      throw InputError("tau: expected " + std::to_string(num_joints_) +
                       " finite values (the writer was made with torques=True)");
    if (!torques_ && tau) throw InputError("tau: the writer was made with torques=False");
    last_t_ = t;
    ++samples_;
    if (torques_)
      writer_->AddJointSample(t, q, *tau);
    else
      writer_->AddJointSample(t, q, Eigen::VectorXd());
  }

  void AddCameraFrame(
      double t, const py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>& image,
      const Mat4& T_PC) {
    Writable();
    if (!camera_) throw InputError("add_camera_frame: the writer was made without K");
    if (!std::isfinite(t)) throw InputError("add_camera_frame: t is not finite");
    const Image8 im = ImageFrom(image);
    if (im.width != width_ || im.height != height_ || im.channels != 3)
      throw InputError("add_camera_frame: expected a " + std::to_string(height_) + " x " +
                       std::to_string(width_) + " x 3 image, got " + std::to_string(im.height) +
                       " x " + std::to_string(im.width) + " x " + std::to_string(im.channels));
    const Transform T = ToTransform(T_PC, "T_PC");
    py::gil_scoped_release release;
    writer_->AddCameraFrame(t, im, T);
  }

  void AddGroundTruth(double t, const Mat4& T_PO) {
    Writable();
    if (!std::isfinite(t)) throw InputError("add_ground_truth: t is not finite");
    writer_->AddGroundTruth(t, ToTransform(T_PO, "T_PO"));
  }

  void AddFile(const std::string& relative_path, const std::string& contents) {
    Writable();
    const std::filesystem::path p(relative_path);
    if (p.empty() || p.is_absolute() ||
        std::any_of(p.begin(), p.end(), [](const std::filesystem::path& c) { return c == ".."; }))
      throw InputError("add_file: " + relative_path + ": expected a path inside the session");
    writer_->AddFile(relative_path, contents);
  }

  void Commit() {
    Writable();
    if (samples_ < 2) throw InputError("commit: a session needs at least two joint samples");
    py::gil_scoped_release release;
    writer_->Commit();
    writer_.reset();
    committed_ = true;
  }

  // Drops everything written (the session never appears).
  void Discard() { writer_.reset(); }

 private:
  void Writable() const {
    if (!writer_)
      throw InputError(committed_ ? "SessionWriter: already committed"
                                  : "SessionWriter: discarded");
  }

  long num_joints_;
  bool torques_;
  bool camera_ = false;
  int width_ = 0, height_ = 0;
  double last_t_ = -std::numeric_limits<double>::infinity();
  long samples_ = 0;
  bool committed_ = false;
  std::unique_ptr<SessionWriter> writer_;
};

// The Tracker with the models it refers to kept alive by Python (keep_alive on construction),
// and the joint vectors checked against the hand before they reach it.
class PyTracker {
 public:
  PyTracker(const HandModel& hand, const ObjectModel& object, const std::string& set,
            const py::object& params, bool threaded, double horizon, int history_samples,
            int max_queued_images)
      : hand_(hand) {
    TrackerOptions options;
    options.threaded = threaded;
    options.horizon = horizon;
    options.history_samples = history_samples;
    options.max_queued_images = max_queued_images;
    if (!(horizon > 0.0) || history_samples < 2 || max_queued_images < 1)
      throw InputError(
          "Tracker: expected horizon > 0, history_samples >= 2, max_queued_images >= 1");
    tracker_ = std::make_unique<Tracker>(hand, object, Modalities::Parse(set, "set"),
                                         ParamsFrom(params), options);
  }

  void Start(double t, const Mat4& T_PO, double sigma_position, double sigma_orientation,
             double sigma_bias) {
    StartSigmas sigmas;
    sigmas.position = sigma_position;
    sigmas.orientation = sigma_orientation;
    sigmas.bias = sigma_bias;
    sigmas.Validate("start");
    tracker_->Start(t, ToTransform(T_PO, "T_PO"), sigmas);
    start_called_ = true;
  }

  void AddJointSample(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const std::optional<Eigen::Ref<const Eigen::VectorXd>>& tau) {
    const long n = hand_.num_q();
    if (q.size() != n)
      throw InputError("q: " + std::to_string(q.size()) + " values, the hand has " +
                       std::to_string(n) + " joints");
    if (tau && tau->size() != n)
      throw InputError("tau: " + std::to_string(tau->size()) + " values, the hand has " +
                       std::to_string(n) + " joints");
    if (!started_check()) throw InputError("add_joint_sample before start");
    py::gil_scoped_release release;
    if (tau) {
      tracker_->AddJointSample(t, q, *tau);
    } else {
      if (zeros_.size() != n) zeros_ = Eigen::VectorXd::Zero(n);
      tracker_->AddJointSample(t, q, zeros_);
    }
  }

  void AddImage(double t_capture,
                const py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>& image,
                const Mat4& T_PC, const Mat3& K, const std::vector<double>& distortion) {
    Image8 im = ImageFrom(image);
    const Intrinsics in = IntrinsicsFrom(K, im.width, im.height, distortion);
    const Transform T = ToTransform(T_PC, "T_PC");
    if (!started_check()) throw InputError("add_image before start");
    py::gil_scoped_release release;
    tracker_->AddImage(t_capture, im, T, in);
  }

  // The C++ Tracker treats a sample before Start as a programming error (it aborts); Python
  // gets an exception.
  bool started_check() const { return start_called_; }
  Tracker& tracker() { return *tracker_; }
  const HandModel& hand() const { return hand_; }

  py::list TakeEvents() {
    std::vector<TrackerEvent> events;
    tracker_->TakeEvents(events);
    py::list out;
    for (const TrackerEvent& e : events) {
      py::dict d;
      d["t"] = e.t;
      d["kind"] = EventKindName(e.kind);
      d["subject"] = EventSubject(e, hand_);
      d["value"] = e.value;
      d["count"] = e.count;
      d["duration"] = e.duration;
      d["message"] = EventMessage(e, hand_);
      out.append(d);
    }
    return out;
  }

 private:
  const HandModel& hand_;
  std::unique_ptr<Tracker> tracker_;
  Eigen::VectorXd zeros_;
  bool start_called_ = false;
};

}  // namespace
}  // namespace inhand

PYBIND11_MODULE(inhand, m) {
  using namespace inhand;
  m.doc() =
      "inhand: where the object in a robot hand is. Sessions, hand and object models, and the "
      "online Tracker (an extended Kalman filter over the object pose and joint biases fusing "
      "joints, joint torques, AprilTags and image features). Poses are 4x4 arrays T_AB, frame B "
      "in A; P is the palm, O the object, C the camera.";
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);

  py::class_<HandModel>(m, "Hand", "A hand loaded from its URDF.")
      .def_property_readonly("joint_names", &HandModel::QNames,
                             "Independent joints in the order q, tau and biases use.")
      .def_property_readonly("num_joints", &HandModel::num_q);
  py::class_<ObjectModel>(m, "Object", "An object loaded from its description (.json or .urdf).");

  m.def(
      "load_hand",
      [](const std::string& urdf, const std::map<std::string, std::string>& packages) {
        HandLoadOptions options;
        options.packages.dirs = packages;
        options.load_visual_meshes = true;
        py::gil_scoped_release release;
        return LoadHandModel(urdf, options);
      },
      py::arg("urdf"), py::arg("packages") = std::map<std::string, std::string>{},
      "Loads a hand from its URDF; packages maps ROS package names to directories.");
  m.def(
      "load_object",
      [](const std::string& path, const std::map<std::string, std::string>& packages) {
        PackageMap map;
        map.dirs = packages;
        py::gil_scoped_release release;
        return LoadObjectModel(path, map);
      },
      py::arg("path"), py::arg("packages") = std::map<std::string, std::string>{},
      "Loads an object description (.json or .urdf) with its contact field.");

  py::class_<Session>(m, "Session",
                      "A recorded or simulated session (sessions/FORMAT.md), read and validated "
                      "whole.")
      .def(py::init([](const std::string& dir) {
             py::gil_scoped_release release;
             return Session::Load(dir);
           }),
           py::arg("dir"))
      .def_property_readonly("dir", &Session::dir)
      .def_property_readonly("joint_names", &Session::joint_names,
                             "joints.csv's columns, the order of q and tau.")
      .def_property_readonly(
          "t",
          [](const py::object& self) {
            const Session& s = self.cast<const Session&>();
            return py::array_t<double>(static_cast<py::ssize_t>(s.times().size()), s.times().data(),
                                       self);
          },
          "Joint sample times [s], a read-only view into the session (no copy).")
      .def_property_readonly(
          "q", [](const Session& s) -> const RowMatrix& { return s.q_all(); },
          py::return_value_policy::reference_internal,
          "Joint positions [rad], samples x joints, a read-only view (no copy).")
      .def_property_readonly(
          "tau",
          [](const py::object& self) -> py::object {
            const Session& s = self.cast<const Session&>();
            if (!s.has_torques()) return py::none();
            return py::cast(s.tau_all(), py::return_value_policy::reference_internal, self);
          },
          "Joint torques [N m] like q, or None without torque sensing.")
      .def_property_readonly(
          "frame_times",
          [](const Session& s) {
            std::vector<double> t;
            for (const CameraFrame& f : s.camera_frames()) t.push_back(f.t);
            return t;
          },
          "Capture time of each camera frame [s].")
      .def(
          "camera_pose",
          [](const Session& s, int i) -> Mat4 {
            if (i < 0 || i >= static_cast<int>(s.camera_frames().size()))
              throw InputError("camera_pose: frame " + std::to_string(i) + " of " +
                               std::to_string(s.camera_frames().size()));
            return s.camera_frames()[static_cast<std::size_t>(i)].T_PC.matrix();
          },
          py::arg("i"), "T_PC of frame i.")
      .def(
          "image",
          [](const Session& s, int i) {
            if (i < 0 || i >= static_cast<int>(s.camera_frames().size()))
              throw InputError("image: frame " + std::to_string(i) + " of " +
                               std::to_string(s.camera_frames().size()));
            Image8 image;
            {
              py::gil_scoped_release release;
              image = s.LoadImage(i);
            }
            return ToArray(image);
          },
          py::arg("i"), "Frame i's image, decoded: H x W x 3 uint8 (RGB).")
      .def_property_readonly(
          "K",
          [](const Session& s) -> py::object {
            if (!s.info().camera) return py::none();
            return py::cast(KOf(*s.info().camera));
          },
          "The camera matrix (3x3), or None without a camera.")
      .def_property_readonly(
          "distortion",
          [](const Session& s) -> py::object {
            if (!s.info().camera) return py::none();
            const auto& d = s.info().camera->distortion;
            return py::cast(std::vector<double>(d.begin(), d.end()));
          },
          "k1 k2 p1 p2 k3 (OpenCV's model), or None without a camera.")
      .def_property_readonly("name", [](const Session& s) { return s.info().name; })
      .def_property_readonly(
          "hand_urdf",
          [](const Session& s) {
            return std::filesystem::absolute(s.Resolve(s.info().hand_urdf)).string();
          },
          "The hand's URDF (absolute path).")
      .def_property_readonly(
          "object_file",
          [](const Session& s) {
            return std::filesystem::absolute(s.Resolve(s.info().object)).string();
          },
          "The object description (absolute path).")
      .def_property_readonly("packages", [](const Session& s) { return s.info().packages; })
      .def_property_readonly("joint_stiffness",
                             [](const Session& s) { return s.info().joint_stiffness; })
      .def_property_readonly(
          "provenance",
          [](const Session& s) {
            return py::module_::import("json").attr("loads")(s.info().provenance_json);
          },
          "Where the session comes from (simulator, scenario, seed...), as a dict.")
      .def_property_readonly(
          "image_size",
          [](const Session& s) -> py::object {
            if (!s.info().camera) return py::none();
            return py::make_tuple(s.info().camera->width, s.info().camera->height);
          },
          "(width, height) of the camera images, or None without a camera.")
      .def_property_readonly(
          "truth_samples",
          [](const Session& s) {
            py::list out;
            for (const GroundTruthSample& g : s.groundtruth())
              out.append(py::make_tuple(g.t, Mat4(g.T_PO.matrix())));
            return out;
          },
          "groundtruth.csv as a list of (t, T_PO); empty without ground truth.")
      .def_property_readonly(
          "initial_pose", [](const Session& s) -> Mat4 { return s.info().initial_T_PO.matrix(); })
      .def_property_readonly("sigma_position",
                             [](const Session& s) { return s.info().sigma_position; })
      .def_property_readonly("sigma_orientation",
                             [](const Session& s) { return s.info().sigma_orientation; })
      .def_property_readonly("sigma_joint_bias",
                             [](const Session& s) { return s.info().sigma_joint_bias; })
      .def(
          "truth",
          [](const Session& s, double t) -> py::object {
            if (!s.has_groundtruth()) return py::none();
            return py::cast(Mat4(s.GroundTruthAt(t).matrix()));
          },
          py::arg("t"), "The true T_PO at t (interpolated), or None without ground truth.")
      .def(
          "models",
          [](const Session& s) {
            SessionModels models;
            {
              py::gil_scoped_release release;
              models = LoadSessionModels(s);
            }
            return py::make_tuple(std::move(models.hand), std::move(models.object),
                                  models.joint_columns);
          },
          "(hand, object, columns): the session's models; q[:, columns] is in the hand's order.");

  py::class_<PySessionWriter>(
      m, "SessionWriter",
      "Writes a session (sessions/FORMAT.md) into a temporary folder beside dir and moves it into "
      "place on commit(): an uncommitted or failed writer leaves nothing. As a context manager it "
      "commits when the block ends without an exception and discards otherwise. Paths in "
      "session.json are written as given: absolute, or relative to the session folder.")
      .def(py::init<const std::string&, const std::string&, const std::string&,
                    const std::vector<std::string>&, bool, const std::optional<Mat3>&,
                    const std::optional<std::pair<int, int>>&, const std::vector<double>&,
                    const Mat4&, double, double, double, const std::map<std::string, std::string>&,
                    const std::map<std::string, double>&, const std::string&, const py::object&,
                    bool>(),
           py::arg("dir"), py::arg("hand_urdf"), py::arg("object"), py::arg("joint_names"),
           py::kw_only(), py::arg("torques") = true, py::arg("K") = py::none(),
           py::arg("image_size") = py::none(), py::arg("distortion") = std::vector<double>{},
           py::arg("initial_pose") = Mat4(Mat4::Identity()), py::arg("sigma_position") = 0.020,
           py::arg("sigma_orientation") = 5.0 * M_PI / 180,
           py::arg("sigma_joint_bias") = 5.0 * M_PI / 180,
           py::arg("packages") = std::map<std::string, std::string>{},
           py::arg("joint_stiffness") = std::map<std::string, double>{}, py::arg("name") = "",
           py::arg("provenance") = py::none(), py::arg("overwrite") = false)
      .def("add_joint_sample", &PySessionWriter::AddJointSample, py::arg("t"), py::arg("q"),
           py::arg("tau") = py::none(),
           "A joint sample in joint_names' order (times strictly increasing); tau when the writer "
           "has torques.")
      .def("add_camera_frame", &PySessionWriter::AddCameraFrame, py::arg("t"), py::arg("image"),
           py::arg("T_PC"), "An RGB image of image_size (written as PNG) and its camera pose.")
      .def("add_ground_truth", &PySessionWriter::AddGroundTruth, py::arg("t"), py::arg("T_PO"))
      .def("add_file", &PySessionWriter::AddFile, py::arg("relative_path"), py::arg("contents"),
           "Any extra text file inside the session.")
      .def("commit", &PySessionWriter::Commit,
           "Writes session.json and moves the session into place.")
      .def("discard", &PySessionWriter::Discard, "Drops the session written so far.")
      .def("__enter__", [](PySessionWriter& w) -> PySessionWriter& { return w; })
      .def("__exit__",
           [](PySessionWriter& w, const py::object& type, const py::object&, const py::object&) {
             if (type.is_none())
               w.Commit();
             else
               w.Discard();
             return false;
           });

  m.def(
      "set_colour",
      [](const std::string& set) {
        const Rgb c = app::ModalityColour(set);
        return py::make_tuple(c.r, c.g, c.b);
      },
      py::arg("set"),
      "A set's colour in every picture and plot, (r, g, b) 0-255: the paper's for j, jt, jta, "
      "jtf; the truth's for a name that is no set.");
  m.def(
      "scenarios",
      [] {
        py::list out;
        for (const ScenarioInfo& s : ListScenarios()) {
          py::dict d;
          d["name"] = s.name;
          d["description"] = s.description;
          d["duration"] = s.duration;
          out.append(d);
        }
        return out;
      },
      "The simulator's scenarios: name, description, duration [s].");
  m.def(
      "simulate",
      [](const std::string& scenario, const std::string& out, unsigned seed,
         const std::string& noise, bool images, bool overwrite, const std::string& effects,
         const std::string& without) {
        app::SimulateCommand cmd;
        cmd.scenario = scenario;
        cmd.out = out;
        cmd.seed = seed;
        cmd.noise = noise;
        cmd.no_images = !images;
        cmd.overwrite = overwrite;
        cmd.effects = effects;
        cmd.without = without;
        const SimulateOptions options = app::SimulateOptionsOf(cmd);
        SimulationSummary summary;
        {
          py::gil_scoped_release release;
          summary = Simulate(options);
        }
        return SimulationDict(summary);
      },
      py::arg("scenario"), py::arg("out"), py::kw_only(), py::arg("seed") = 1u,
      py::arg("noise") = "paper", py::arg("images") = true, py::arg("overwrite") = false,
      py::arg("effects") = "", py::arg("without") = "",
      "Simulates a scenario into the session folder out, as `inhand simulate`; returns what it "
      "measured (duration, samples, frames, penetration, held fraction, rotation, lift).");
  m.def(
      "replay",
      [](const std::string& session, const std::string& out, const std::string& sets,
         const py::object& params, bool video, bool frames, bool timeline, bool mcap, int jobs,
         double picture_memory) {
        const ParamsFile params_file(params);
        app::ReplayCommand cmd;
        cmd.session = session;
        cmd.out = out;
        cmd.modalities = sets;
        cmd.params = params_file.path();
        cmd.no_video = !video;
        cmd.frames = frames;
        cmd.no_timeline = !timeline;
        cmd.mcap = mcap;
        cmd.jobs = jobs;
        cmd.picture_memory_mib = picture_memory;
        int code = 0;
        {
          py::gil_scoped_release release;
          code = app::RunReplay(cmd);
        }
        if (code != 0) throw InputError("replay: failed with code " + std::to_string(code));
        return JsonFile((std::filesystem::path(out) / "summary.json").string());
      },
      py::arg("session"), py::arg("out"), py::kw_only(), py::arg("sets") = "",
      py::arg("params") = py::none(), py::arg("video") = true, py::arg("frames") = false,
      py::arg("timeline") = true, py::arg("mcap") = false, py::arg("jobs") = 2,
      py::arg("picture_memory") = app::ReplayCommand().picture_memory_mib,
      "Replays a session with each set (\"\": every set it supports) into out, as `inhand "
      "replay`; returns summary.json as a dict. params: None, a dict, JSON text or a path. "
      "picture_memory: MiB the pictures may hold until the events are known (the timeline "
      "strip); beyond it the sets run twice, first without pictures.");
  m.def(
      "evaluate",
      [](const std::string& out, const std::string& scenarios, int seeds, int first_seed,
         const std::string& noise, const std::string& sets, const py::object& params, int jobs,
         bool keep_sessions, const std::string& inhand_binary) {
        const ParamsFile params_file(params);
        app::EvaluateCommand cmd;
        cmd.out = out;
        cmd.scenarios = scenarios;
        cmd.seeds = seeds;
        cmd.first_seed = first_seed;
        cmd.noise = noise;
        cmd.modalities = sets;
        cmd.params = params_file.path();
        cmd.jobs = jobs;
        cmd.keep_sessions = keep_sessions;
        const std::string binary = InhandBinary(inhand_binary);
        int code = 0;
        {
          py::gil_scoped_release release;
          code = app::RunEvaluate(cmd, binary);
        }
        if (code != 0) throw InputError("evaluate: failed with code " + std::to_string(code));
        return JsonFile((std::filesystem::path(out) / "table1.json").string());
      },
      py::arg("out"), py::kw_only(), py::arg("scenarios") = "", py::arg("seeds") = 5,
      py::arg("first_seed") = 1, py::arg("noise") = "paper", py::arg("sets") = "j,jt,jta,jtf",
      py::arg("params") = py::none(), py::arg("jobs") = 2, py::arg("keep_sessions") = false,
      py::arg("inhand_binary") = "",
      "Simulates and replays every scenario x seed (as `inhand evaluate`, runs in parallel "
      "processes of the inhand command) into out; returns table1.json as a dict.");

  py::class_<PyTracker>(m, "Tracker",
                        "The online estimator of one set (j, jt, jta, jtf, ...). Joint samples at "
                        "joint rate; images whenever they arrive, fused at their capture time.")
      .def(py::init<const HandModel&, const ObjectModel&, const std::string&, const py::object&,
                    bool, double, int, int>(),
           py::arg("hand"), py::arg("object"), py::arg("set") = "jt",
           py::arg("params") = py::none(), py::arg("threaded") = false, py::arg("horizon") = 0.5,
           py::arg("history_samples") = 2048, py::arg("max_queued_images") = 2,
           py::keep_alive<1, 2>(), py::keep_alive<1, 3>())
      .def("start", &PyTracker::Start, py::arg("t"), py::arg("T_PO"),
           py::arg("sigma_position") = 0.020, py::arg("sigma_orientation") = 5.0 * M_PI / 180,
           py::arg("sigma_bias") = 5.0 * M_PI / 180,
           "Starts at time t from the guess T_PO with its standard deviations [m, rad, rad].")
      .def("add_joint_sample", &PyTracker::AddJointSample, py::arg("t"), py::arg("q"),
           py::arg("tau") = py::none(),
           "A joint sample in the hand's joint order: positions [rad], external torques [N m] "
           "(None: zeros, for hands without torque sensing).")
      .def("add_image", &PyTracker::AddImage, py::arg("t_capture"), py::arg("image"),
           py::arg("T_PC"), py::arg("K"), py::arg("distortion") = std::vector<double>{},
           "A camera image captured at t_capture by a camera at T_PC (palm frame) with camera "
           "matrix K and optional distortion (k1 k2 p1 p2 k3).")
      .def(
          "wait_for_images",
          [](PyTracker& t) {
            py::gil_scoped_release release;
            t.tracker().WaitForImages();
          },
          "Threaded: waits until every image added has been fused.")
      .def_property_readonly("t", [](PyTracker& t) { return t.tracker().t(); })
      .def(
          "pose", [](PyTracker& t) -> Mat4 { return t.tracker().T_PO().matrix(); },
          "T_PO, the object in the palm frame (4x4).")
      .def(
          "covariance", [](PyTracker& t) { return t.tracker().covariance(); },
          "The filter's covariance of (position, orientation, joint biases), 6 + joints square.")
      .def(
          "claimed_pose_covariance",
          [](PyTracker& t) -> Mat6 { return t.tracker().claimed_pose_covariance(); },
          "The covariance of (position, orientation) the estimate claims (6x6): the filter's, "
          "widened by what the health knows (a pressing finger in the air, a link inside the "
          "object: that distance on the position, and as the turn that moves the object's points "
          "as far on the orientation). What sigma, NEES and the HUD report.")
      .def(
          "biases", [](PyTracker& t) -> Eigen::VectorXd { return t.tracker().biases(); },
          "Joint position biases [rad].")
      .def(
          "stats", [](PyTracker& t) { return StatsDict(t.tracker().stats()); },
          "Counts of samples and images fused, dropped, rejected; relocalizations, recoveries.")
      .def(
          "health", [](PyTracker& t) { return HealthDict(t.tracker().health(), t.hand()); },
          "The set's own judgement: state (ok, uncertain, inconsistent, lost), cause, message.")
      .def("take_events", &PyTracker::TakeEvents,
           "The events found since the last call (contacts, lost features, health changes...).");
}
