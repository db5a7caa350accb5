// The realistic profile's effects: realism.hpp (object, hand, torques) and camera_sim.hpp (the
// camera) in one file, as they share the helpers below.
#include "inhand/sessions/camera_sim.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "inhand/core/error.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/io/mesh_io.hpp"
#include "inhand/renderer/renderer.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kNumEffects = static_cast<std::size_t>(Effect::kCount);

// sRGB-like transfer (gamma 2.2): what the renderer's 8-bit colours mean, and what the camera
// writes (tables: the transfer runs for every pixel of every sub-frame).
const std::array<float, 256>& ToLinearTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[static_cast<std::size_t>(i)] = std::pow(i / 255.0f, 2.2f);
    return t;
  }();
  return table;
}
constexpr int kEncodeSteps = 1 << 16;
const std::array<std::uint8_t, kEncodeSteps + 1>& EncodeTable() {
  static const std::array<std::uint8_t, kEncodeSteps + 1> table = [] {
    std::array<std::uint8_t, kEncodeSteps + 1> t{};
    for (int i = 0; i <= kEncodeSteps; ++i)
      t[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(
          std::lround(255.0 * std::pow(double(i) / kEncodeSteps, 1.0 / 2.2)));
    return t;
  }();
  return table;
}

}  // namespace

const char* EffectName(Effect e) {
  switch (e) {
    case Effect::kObjectScale:
      return "object.scale";
    case Effect::kObjectTags:
      return "object.tags";
    case Effect::kObjectColour:
      return "object.colour";
    case Effect::kHandGeometry:
      return "hand.geometry";
    case Effect::kHandDeflection:
      return "hand.deflection";
    case Effect::kHandPads:
      return "hand.pads";
    case Effect::kTorqueDrift:
      return "torque.drift";
    case Effect::kTorqueResidue:
      return "torque.residue";
    case Effect::kTorqueLag:
      return "torque.lag";
    case Effect::kCameraLight:
      return "camera.light";
    case Effect::kCameraExposure:
      return "camera.exposure";
    case Effect::kCameraVignetting:
      return "camera.vignetting";
    case Effect::kCameraDistortion:
      return "camera.distortion";
    case Effect::kCameraMotionBlur:
      return "camera.motion_blur";
    case Effect::kCameraSensorNoise:
      return "camera.sensor_noise";
    case Effect::kCameraJpeg:
      return "camera.jpeg";
    case Effect::kCameraIntrinsics:
      return "camera.intrinsics";
    case Effect::kObjectMesh:
      return "object.mesh";
    case Effect::kCount:
      break;
  }
  return "?";
}

Effects Effects::All() {
  Effects e;
  e.bits_.set();
  return e;
}

Effects Effects::Parse(const std::string& list, const std::string& option) {
  Effects e;
  std::stringstream ss(list);
  std::string name;
  while (std::getline(ss, name, ',')) {
    name.erase(0, name.find_first_not_of(' '));
    name.erase(name.find_last_not_of(' ') + 1);
    if (name.empty()) continue;
    bool found = false;
    for (std::size_t i = 0; i < kNumEffects; ++i) {
      const std::string full = EffectName(static_cast<Effect>(i));
      const std::string group = full.substr(0, full.find('.'));
      if (name == "all" || name == full || name == group) {
        e.bits_.set(i);
        found = true;
      }
    }
    if (!found) {
      std::string names = "all, object, hand, torque, camera";
      for (std::size_t i = 0; i < kNumEffects; ++i)
        names += std::string(", ") + EffectName(static_cast<Effect>(i));
      throw InputError(option + ": effect '" + name +
                       "' is unknown, expected a comma-separated list of: " + names);
    }
  }
  return e;
}

Effects Effects::Without(const Effects& other) const {
  Effects e;
  e.bits_ = bits_ & ~other.bits_;
  return e;
}

bool Effects::AnyCamera() const {  // light to JPEG: the intrinsics' error needs no simulation
  for (std::size_t i = static_cast<std::size_t>(Effect::kCameraLight);
       i <= static_cast<std::size_t>(Effect::kCameraJpeg); ++i)
    if (bits_[i]) return true;
  return false;
}

std::vector<std::string> Effects::Names() const {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < kNumEffects; ++i)
    if (bits_[i]) out.emplace_back(EffectName(static_cast<Effect>(i)));
  return out;
}

ObjectModel ScaledObject(const ObjectModel& object, const Vec3& s) {
  ObjectModel w = object;
  for (TriangleMesh& m : w.visual) m.ScaleBy(s);
  for (ConvexPiece& p : w.pieces) {
    TriangleMesh hull = p.ToMesh();  // in the object frame
    hull.ScaleBy(s);
    ConvexPiece scaled = ConvexPiece::Hull(hull.vertices, hull.triangles);
    scaled.source = p.source + " (scaled)";
    p = std::move(scaled);
  }
  const double f = s.x() * s.y() * s.z();
  w.mass = object.mass * f;
  w.com_O = s.cwiseProduct(object.com_O);
  // Inertia from the second moment M = ∫ x xᵀ dm, which maps to f S M S.
  const Mat3 M = 0.5 * object.inertia_com.trace() * Mat3::Identity() - object.inertia_com;
  const Mat3 S = s.asDiagonal();
  const Mat3 M2 = f * S * M * S;
  w.inertia_com = M2.trace() * Mat3::Identity() - M2;
  for (TagPlacement& t : w.tags) t.T_OT.translation() = s.cwiseProduct(t.T_OT.translation());
  w.field = nullptr;
  w.field_cache.clear();
  w.decomposition = object.decomposition + ", scaled";
  return w;
}

SimplifiedModel SimplifyModel(const ObjectModel& model, const std::string& object_json,
                              const std::string& object_dir, const RealismParams& params) {
  SimplifiedModel out;
  std::vector<TriangleMesh> meshes;
  std::vector<std::string> textures;
  for (std::size_t i = 0; i < model.visual.size(); ++i) {
    const TriangleMesh& m = model.visual[i];
    const auto target = static_cast<std::size_t>(
        std::ceil(params.simplify_fraction * static_cast<double>(m.num_triangles())));
    meshes.push_back(SimplifyMesh(m, target, params.simplify_error));
    out.triangles_before += m.num_triangles();
    out.triangles_after += meshes.back().num_triangles();
    std::string texture;
    if (!m.material.texture_file.empty()) {
      texture = fs::relative(m.material.texture_file, object_dir).generic_string();
    } else if (!m.material.texture_blob.empty()) {
      texture = "simplified_texture_" + std::to_string(i) + ".png";
      out.files.emplace_back(
          texture, std::string(m.material.texture_blob.begin(), m.material.texture_blob.end()));
    }
    textures.push_back(texture);
  }
  const ObjText text = MeshesObjText(meshes, "simplified.mtl", textures);
  const std::vector<ConvexPiece> pieces =
      SlabHulls(meshes, params.slab, params.max_slabs, model.name + " (simplified)");
  out.pieces_before = model.pieces.size();
  out.pieces_after = pieces.size();
  jsonf::Json doc;
  try {
    doc = jsonf::Json::parse(object_json);
  } catch (const std::exception& e) {
    throw InputError(model.source + ": " + e.what());
  }
  doc["visual"] = jsonf::Json::array({{{"mesh", "simplified.obj"}}});
  doc["collision"] =
      jsonf::Json::array({{{"mesh", "simplified_pieces.obj"}, {"method", "components"}}});
  out.files.emplace_back("simplified.obj", text.obj);
  out.files.emplace_back("simplified.mtl", text.mtl);
  out.files.emplace_back("simplified_pieces.obj", PiecesObjText(pieces));
  out.files.emplace_back("object.json", doc.dump(2) + "\n");
  return out;
}

void TintObject(ObjectModel& object, const Vec3& gains) {
  for (TriangleMesh& m : object.visual) {
    m.material.rgba.head<3>() = m.material.rgba.head<3>().cwiseProduct(gains).cwiseMin(1.0);
    if (!m.material.HasTexture()) continue;
    const std::string what = object.source + ": texture of material '" + m.material.name + "'";
    Image8 rgb =
        m.material.texture_blob.empty()
            ? ReadImage(m.material.texture_file)
            : DecodeImage(m.material.texture_blob.data(), m.material.texture_blob.size(), what);
    cv::Mat tex(rgb.height, rgb.width, CV_8UC3, rgb.data.data()), f;
    tex.convertTo(f, CV_32FC3);
    cv::multiply(f, cv::Scalar(gains.x(), gains.y(), gains.z()), f);  // RGB
    f.convertTo(tex, CV_8UC3);                                        // saturates, in place
    m.material.texture_blob = EncodePng(rgb);
    m.material.texture_file.clear();
  }
}

Vec3 RandomUnitVector(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

void MisplaceTags(ObjectModel& object, double position, double orientation, std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(0.0, 2 * M_PI);
  for (TagPlacement& t : object.tags) {
    const double a = angle(rng);
    t.T_OT.translation() += position * (t.T_OT.linear() * Vec3(std::cos(a), std::sin(a), 0.0));
    t.T_OT.linear() = t.T_OT.linear() * ExpSO3(orientation * RandomUnitVector(rng));
  }
}

HandModel PerturbedHand(const HandModel& hand, double sigma, std::mt19937& rng,
                        std::vector<Vec3>* offsets) {
  HandModel h = hand;
  std::normal_distribution<double> n(0.0, sigma);
  if (offsets) offsets->clear();
  for (Joint& j : h.joints) {
    const Vec3 d(n(rng), n(rng), n(rng));
    j.T_LJ.translation() += d;
    if (offsets) offsets->push_back(d);
  }
  return h;
}

TorqueErrors::TorqueErrors(int joints, const RealismParams& params, const Effects& effects,
                           std::mt19937& rng)
    : params_(params),
      effects_(effects),
      rng_(rng()),
      drift_(Eigen::VectorXd::Zero(joints)),
      lagged_(Eigen::VectorXd::Zero(joints)) {
  std::normal_distribution<double> n(0.0, 1.0);
  if (effects_.Has(Effect::kTorqueDrift))
    for (int j = 0; j < joints; ++j) drift_[j] = params_.drift_sigma * n(rng_);  // stationary start
}

Eigen::VectorXd TorqueErrors::Step(double dt, const Eigen::VectorXd& tau_contact,
                                   const Eigen::VectorXd& q_dot,
                                   const Eigen::VectorXd& tau_gravity) {
  Eigen::VectorXd tau = tau_contact;
  if (effects_.Has(Effect::kTorqueDrift)) {
    std::normal_distribution<double> n(0.0, 1.0);
    const double a = std::exp(-dt / params_.drift_time);
    const double b = params_.drift_sigma * std::sqrt(1.0 - a * a);
    for (int j = 0; j < drift_.size(); ++j) drift_[j] = a * drift_[j] + b * n(rng_);
    tau += drift_;
  }
  if (effects_.Has(Effect::kTorqueResidue)) {
    for (int j = 0; j < tau.size(); ++j)
      tau[j] += params_.friction_residue * std::tanh(q_dot[j] / params_.friction_velocity);
    tau += params_.gravity_residue * tau_gravity;
  }
  if (!effects_.Has(Effect::kTorqueLag)) return tau;
  if (!started_) lagged_ = tau;
  started_ = true;
  lagged_ += (dt / (dt + params_.torque_lag)) * (tau - lagged_);
  return lagged_;
}

CameraSimulator::CameraSimulator(Renderer& renderer, const Intrinsics& K_true,
                                 const RealismParams& params, const Effects& effects,
                                 const LightRig& light, unsigned seed)
    : renderer_(renderer),
      K_(K_true),
      params_(params),
      effects_(effects),
      light_(light),
      rng_(seed) {
  if (!effects_.Has(Effect::kCameraDistortion)) K_.distortion = {0, 0, 0, 0, 0};
  const int W = K_.width, H = K_.height;
  map_x_.resize(std::size_t(W) * H);
  map_y_.resize(map_x_.size());
  double over = 0.0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const Vec2 u = K_.Undistort(Vec2(x, y));  // where the ideal pinhole image has it
      map_x_[std::size_t(y) * W + x] = static_cast<float>(u.x());
      map_y_[std::size_t(y) * W + x] = static_cast<float>(u.y());
      over = std::max({over, -u.x(), u.x() - (W - 1), -u.y(), u.y() - (H - 1)});
    }
  margin_ = static_cast<int>(std::ceil(over)) + 2;
  for (std::size_t i = 0; i < map_x_.size(); ++i) {
    map_x_[i] += static_cast<float>(margin_);
    map_y_[i] += static_cast<float>(margin_);
  }
}

void CameraSimulator::RenderShadowMap(const Scene& scene) {
  shadow_scene_ = scene;
  shadow_scene_.K = Intrinsics();
  shadow_scene_.K.width = shadow_scene_.K.height = kShadowSize;
  shadow_scene_.K.fx = shadow_scene_.K.fy = 0.5 * kShadowSize / std::tan(40.0 * M_PI / 180);
  shadow_scene_.K.cx = shadow_scene_.K.cy = 0.5 * kShadowSize - 0.5;
  shadow_scene_.T_PC = LookAt(light_.lamp, light_.lamp_target, Vec3::UnitZ());
  for (SceneItem& item : shadow_scene_.items) item.unlit = true;
  RenderOutput shadow;
  renderer_.Render(shadow_scene_, shadow, true);
  shadow_depth_ = std::move(shadow.depth);
}

void CameraSimulator::RenderPadded(const Scene& scene, std::vector<float>& rgb) {
  const bool relight = effects_.Has(Effect::kCameraLight);
  Scene s = scene;
  s.K.distortion = {0, 0, 0, 0, 0};
  s.K.width += 2 * margin_;
  s.K.height += 2 * margin_;
  s.K.cx += margin_;
  s.K.cy += margin_;
  if (relight)
    for (SceneItem& item : s.items) item.unlit = true;  // albedo only
  RenderOutput out;
  renderer_.Render(s, out, relight);
  const int W = s.K.width, H = s.K.height;
  const std::size_t n = std::size_t(W) * H;
  const std::array<float, 256>& lin = ToLinearTable();
  rgb.resize(3 * n);
  for (std::size_t i = 0; i < 3 * n; ++i) rgb[i] = lin[out.colour.data[i]];
  if (!relight) return;

  // Points (camera frame) and normals (central differences, each axis from the side whose
  // depth continues).
  points_.resize(n);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const float z = out.depth_at(x, y);
      points_[std::size_t(y) * W + x] =
          std::isfinite(z) ? s.K.Unproject(Vec2(x, y), z) : Vec3(0, 0, -1);
    }
  const auto side = [&](int x, int y, int dx, int dy) -> Vec3 {
    const Vec3& p = points_[std::size_t(y) * W + x];
    Vec3 best = Vec3::Zero();
    double best_dz = 0.02;  // [m] no difference across a depth discontinuity
    for (int sgn : {1, -1}) {
      const int xx = x + sgn * dx, yy = y + sgn * dy;
      if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
      const Vec3& q = points_[std::size_t(yy) * W + xx];
      if (q.z() < 0) continue;
      const double dz = std::abs(q.z() - p.z());
      if (dz < best_dz) {
        best_dz = dz;
        best = sgn * (q - p);
      }
    }
    return best;
  };
  const Intrinsics& KL = shadow_scene_.K;
  const Transform T_LP = shadow_scene_.T_PC.inverse();
  const Mat3 R = s.T_PC.linear();
  const Vec3 eye = s.T_PC.translation();
  const double d_target2 = (light_.lamp - light_.lamp_target).squaredNorm();
  const Vec3 fill = light_.fill_direction.normalized();
  const Vec3 bg(std::pow(scene.background.x(), 2.2), std::pow(scene.background.y(), 2.2),
                std::pow(scene.background.z(), 2.2));
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const std::size_t i = std::size_t(y) * W + x;
      float* px = &rgb[3 * i];
      if (points_[i].z() < 0) {
        for (int c = 0; c < 3; ++c) px[c] = static_cast<float>(bg[c]);
        continue;
      }
      const Vec3 n_C = side(x, y, 1, 0).cross(side(x, y, 0, 1));
      const Vec3 P = s.T_PC * points_[i];
      const Vec3 view = (eye - P).normalized();
      Vec3 nrm = n_C.squaredNorm() > 0 ? Vec3(R * n_C.normalized()) : view;
      if (nrm.dot(view) < 0) nrm = -nrm;
      const Vec3 L = light_.lamp - P;
      const double d2 = L.squaredNorm();
      const Vec3 l = L / std::sqrt(d2);
      const double cos_l = nrm.dot(l);
      double lamp = 0.0, spec = 0.0;
      if (cos_l > 0) {
        // Percentage-closer filtering over 3x3 texels of the shadow map.
        const Vec3 X_L = T_LP * P;
        const Vec2 uv = KL.Project(X_L);
        const double bias = 0.003 + 0.006 * (1.0 - cos_l);
        const int u0 = static_cast<int>(std::floor(uv.x() + 0.5)),
                  v0 = static_cast<int>(std::floor(uv.y() + 0.5));
        int lit = 0;
        for (int v = v0 - 1; v <= v0 + 1; ++v)
          for (int u = u0 - 1; u <= u0 + 1; ++u)
            lit += u < 0 || v < 0 || u >= KL.width || v >= KL.height ||
                   X_L.z() <= shadow_depth_[std::size_t(v) * KL.width + u] + bias;
        const double visible = lit / 9.0;
        const double power = light_.lamp_power * visible * d_target2 / d2;
        lamp = power * cos_l;
        const double nh = std::max(nrm.dot((l + view).normalized()), 0.0);
        if (visible > 0 && nh > 0.7)
          spec = light_.specular * power * std::pow(nh, light_.shininess);
      }
      const Vec3 E = light_.ambient + light_.lamp_colour * lamp +
                     light_.fill_colour * std::max(nrm.dot(fill), 0.0);
      for (int c = 0; c < 3; ++c)
        px[c] = static_cast<float>(px[c] * E[c] + light_.lamp_colour[c] * spec);
    }
}

std::vector<float> CameraSimulator::Radiance(const Scene& scene) {
  if (effects_.Has(Effect::kCameraLight)) RenderShadowMap(scene);
  std::vector<float> rgb;
  RenderPadded(scene, rgb);
  return rgb;
}

void CameraSimulator::Capture(const std::vector<Scene>& subframes, Image8& out) {
  INHAND_CHECK(!subframes.empty(), "CameraSimulator::Capture needs a scene");
  const int W = K_.width, H = K_.height;
  const int PW = W + 2 * margin_, PH = H + 2 * margin_;
  // The shadows of the exposure's end (the scene moves by a millimetre at most within it).
  if (effects_.Has(Effect::kCameraLight)) RenderShadowMap(subframes.back());
  // Exposure over the sub-frames (motion blur), in linear light.
  cv::Mat sum(PH, PW, CV_32FC3, cv::Scalar(0, 0, 0));
  for (const Scene& s : subframes) {
    RenderPadded(s, rgb_);
    sum += cv::Mat(PH, PW, CV_32FC3, rgb_.data());
  }
  sum /= static_cast<double>(subframes.size());
  // The lens: distorted output pixels sample the ideal image.
  cv::Mat img;
  cv::remap(sum, img, cv::Mat(H, W, CV_32F, map_x_.data()), cv::Mat(H, W, CV_32F, map_y_.data()),
            cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  // Exposure and white balance drift: AR(1) per frame in log gain, started stationary.
  std::normal_distribution<double> n01(0.0, 1.0);
  if (effects_.Has(Effect::kCameraExposure)) {
    const double rho = 0.8, innov = std::sqrt(1.0 - rho * rho);
    if (!started_) {
      exposure_ = params_.exposure_sigma * n01(rng_);
      for (int c = 0; c < 3; ++c) white_balance_[c] = params_.white_balance_sigma * n01(rng_);
    } else {
      exposure_ = rho * exposure_ + innov * params_.exposure_sigma * n01(rng_);
      for (int c = 0; c < 3; ++c)
        white_balance_[c] =
            rho * white_balance_[c] + innov * params_.white_balance_sigma * n01(rng_);
    }
    started_ = true;
  } else {
    exposure_ = 0.0;
    white_balance_.setZero();
  }
  const Vec3 gain = (exposure_ + white_balance_.array()).exp();
  const bool vignette = effects_.Has(Effect::kCameraVignetting);
  const double r_max2 = 0.25 * (double(W) * W + double(H) * H);
  cv::Mat noise;
  if (effects_.Has(Effect::kCameraSensorNoise)) {
    noise.create(H, W, CV_32FC3);
    cv::RNG noise_rng(rng_());  // seeded from the camera's stream: deterministic
    noise_rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  }
  const std::array<std::uint8_t, kEncodeSteps + 1>& encode = EncodeTable();
  out = Image8(W, H, 3);
  for (int y = 0; y < H; ++y) {
    const cv::Vec3f* row = img.ptr<cv::Vec3f>(y);
    const cv::Vec3f* nrow = noise.empty() ? nullptr : noise.ptr<cv::Vec3f>(y);
    for (int x = 0; x < W; ++x) {
      double v = 1.0;
      if (vignette) {
        const double dx = x - K_.cx, dy = y - K_.cy;
        v = 1.0 - params_.vignetting * (dx * dx + dy * dy) / r_max2;
      }
      std::uint8_t* px = out.pixel(x, y);
      for (int c = 0; c < 3; ++c) {
        double s = std::max(0.0, double(row[x][c]) * v * gain[c]);
        if (nrow) {  // shot noise (Poisson, as a Gaussian of its variance) and read noise, in
                     // electrons
          const double e = s * params_.full_well;
          s = (e + std::sqrt(e + params_.read_noise * params_.read_noise) * nrow[x][c]) /
              params_.full_well;
        }
        px[c] = encode[static_cast<std::size_t>(std::clamp(s, 0.0, 1.0) * kEncodeSteps + 0.5)];
      }
    }
  }
  if (effects_.Has(Effect::kCameraJpeg)) {
    const std::vector<std::uint8_t> jpg = EncodeJpeg(out, params_.jpeg_quality);
    out.data = DecodeImage(jpg.data(), jpg.size(), "the simulated camera's JPEG").data;
  }
}

}  // namespace inhand
