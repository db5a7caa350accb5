#include "inhand/app/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/kinematics/kinematics.hpp"

namespace inhand::app {

FilterParams ReadFilterParams(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the parameter file");
  std::stringstream ss;
  ss << in.rdbuf();
  return FilterParamsFromJson(ss.str(), path);
}

std::vector<ModalitySet> ParseModalities(const std::string& list) {
  std::vector<ModalitySet> out;
  std::stringstream ss(list);
  std::string name;
  while (std::getline(ss, name, ',')) {
    if (name == "j") out.push_back({"j", false, false, false, kColourJoints});
    else if (name == "jt") out.push_back({"jt", true, false, false, kColourTorques});
    else if (name == "jta") out.push_back({"jta", true, true, false, kColourTags});
    else if (name == "jtf") out.push_back({"jtf", true, false, true, kColourFeatures});
    else throw InputError("--modalities: unknown set '" + name + "', expected j, jt, jta or jtf");
  }
  if (out.empty()) throw InputError("--modalities: empty list");
  return out;
}

Pipeline::Pipeline(Session& session, const FilterParams& params, std::vector<ModalitySet> sets)
    : session_(session), models_(LoadSessionModels(session, true)), params_(params), sets_(std::move(sets)) {
  params_.Validate();
  if (sets_.empty())
    sets_ = ParseModalities(!session_.info().camera ? "j,jt" : models_.object.tags.empty() ? "j,jt,jtf" : "j,jt,jta,jtf");
  for (const ModalitySet& s : sets_) {
    queries_.push_back(std::make_unique<BulletContactQuery>(models_.hand, models_.object));
    filters_.push_back(std::make_unique<Filter>(models_.hand, *queries_.back(), params_, FilterOptions{s.torque}));
  }
  state_.last.resize(sets_.size());
  bool tags = false, features = false;
  for (const ModalitySet& m : sets_) tags = tags || m.tags, features = features || m.features;
  if (features) {
    if (!session_.info().camera) throw InputError(session_.dir() + ": modality jtf needs camera images, the session has none");
    renderer_ = std::make_unique<Renderer>();
    hand_meshes_ = UploadHand(*renderer_, models_.hand);
    object_meshes_ = UploadObject(*renderer_, models_.object, PrintedTagMeshes(models_.object));  // its appearance
  }
  if (tags) {
    if (!session_.info().camera) throw InputError(session_.dir() + ": modality jta needs camera images, the session has none");
    if (models_.object.tags.empty())
      throw InputError(models_.object.source + ": modality jta needs AprilTags on the object, it has none");
    TagDetectorParams p;
    p.family = models_.object.tags.front().family;
    tag_detector_ = std::make_unique<TagDetector>(p);
    p.decimate = 1.0;
    tag_detector_fine_ = std::make_unique<TagDetector>(p);
  }
}

Pipeline::Checkpoint Pipeline::Save() const {
  Checkpoint c;
  c.filters.reserve(filters_.size());
  for (const auto& f : filters_) c.filters.push_back(*f);
  c.state = state_;
  return c;
}

void Pipeline::Restore(const Checkpoint& c) {
  INHAND_CHECK(c.filters.size() == filters_.size(), "checkpoint of a pipeline with other modality sets");
  for (std::size_t i = 0; i < filters_.size(); ++i) filters_[i] = std::make_unique<Filter>(c.filters[i]);
  state_ = c.state;
}

void Pipeline::Step(int k) {
  const SessionInfo& info = session_.info();
  const double t = session_.t(k);
  const double dt = k > 0 ? t - session_.t(k - 1) : 0.0;
  for (std::size_t i = 0; i < filters_.size(); ++i) {
    Filter& f = *filters_[i];
    const auto start = std::chrono::steady_clock::now();
    if (k == 0) f.Reset(info.initial_T_PO, session_.q(0), StartSigmas{info.sigma_position, info.sigma_orientation, info.sigma_joint_bias, {}});
    f.Predict(session_.q(k), dt);
    f.UpdateContacts(session_.tau(k));
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    EstimateRecord& r = state_.last[i];
    r.t = t;
    r.T_PO = f.T_PO();
    r.sigma_position = f.covariance().diagonal().head<3>().cwiseSqrt();
    r.sigma_orientation = f.covariance().diagonal().segment<3>(3).cwiseSqrt();
    r.biases = f.biases();
    r.step_time_us = us;
    r.constraints = f.trace().num_constraints;
    r.contacts = static_cast<int>(f.trace().contacts.size());
    r.gated = f.trace().num_gated;
    r.visual_ms = -1.0;
    r.visual_used = 0;
  }

  // Camera frames that arrived by this sample: tag corners for the sets that use them.
  const auto& frames = session_.camera_frames();
  state_.last_frame = -1;
  while (state_.next_frame < frames.size() && frames[state_.next_frame].t <= t + 1e-9) {
    const int f = static_cast<int>(state_.next_frame++);
    state_.last_frame = f;
    state_.image = session_.LoadImage(f);
    state_.tags.clear();
    for (std::size_t i = 0; i < filters_.size(); ++i)
      if (sets_[i].features) FeatureUpdate(i, f);
    if (!tag_detector_) continue;
    const Intrinsics& K = *info.camera;
    const auto start = std::chrono::steady_clock::now();
    DetectTags(frames[static_cast<std::size_t>(f)].T_PC, K);
    state_.features.clear();
    for (const TagDetection& d : state_.tags)
      for (const TagPlacement& tag : models_.object.tags) {
        if (tag.id != d.id || tag.family != d.family) continue;
        const auto corners = tag.CornersO();
        for (int c = 0; c < 4; ++c)
          state_.features.push_back({d.id * 4 + c, corners[static_cast<std::size_t>(c)], K.Undistort(d.corners[static_cast<std::size_t>(c)])});
      }
    const double detect_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    for (std::size_t i = 0; i < filters_.size(); ++i) {
      if (!sets_[i].tags) continue;
      const auto update_start = std::chrono::steady_clock::now();
      state_.last[i].visual_used = filters_[i]->UpdateVisual(state_.features, frames[static_cast<std::size_t>(f)].T_PC, K);
      state_.last[i].gated += filters_[i]->trace().num_gated;
      state_.last[i].visual_ms = detect_ms + std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - update_start).count();
      state_.last[i].T_PO = filters_[i]->T_PO();
    }
  }
  for (std::size_t i = 0; i < filters_.size(); ++i) {
    EstimateRecord& r = state_.last[i];
    if (session_.has_groundtruth()) {
      const Transform gt = session_.GroundTruthAt(t);
      r.position_error = (r.T_PO.translation() - gt.translation()).norm();
      r.orientation_error = RotationDistance(r.T_PO.linear(), gt.linear());
      r.position_error_O = gt.linear().transpose() * (r.T_PO.translation() - gt.translation());
      r.orientation_error_O = LogSO3(gt.linear().transpose() * r.T_PO.linear());
      // Normalised estimation error squared of the pose, in the filter's error convention
      // (p = p̂ + δp, R = Exp(δθ) R̂).
      Vec6 e;
      e.head<3>() = gt.translation() - r.T_PO.translation();
      e.tail<3>() = LogSO3(gt.linear() * r.T_PO.linear().transpose());
      const Mat6 P = filters_[i]->covariance().topLeftCorner<6, 6>();
      r.nees = e.dot(P.ldlt().solve(e));
    }
  }
}

// Tags of the whole frame at the detector's decimation (fast, but it loses tags under ~30 px
// wide, as a tag on an object in the hand often is); then each of the object's tags that the
// first tag set's estimate puts in view, facing the camera, and that was not found, is searched
// at full resolution in its expected box, widened by its size (at least 40 px) for the
// estimate's error.
void Pipeline::DetectTags(const Transform& T_PC, const Intrinsics& K) {
  state_.tags = tag_detector_->Detect(state_.image);
  std::size_t set = 0;
  while (set < sets_.size() && !sets_[set].tags) ++set;
  if (set == sets_.size()) return;
  const Transform T_CO = T_PC.inverse() * filters_[set]->T_PO();
  for (const TagPlacement& tag : models_.object.tags) {
    const bool found = std::any_of(state_.tags.begin(), state_.tags.end(),
                                   [&](const TagDetection& d) { return d.id == tag.id && d.family == tag.family; });
    if (found || tag.family != tag_detector_fine_->params().family) continue;
    const Transform T_CT = T_CO * tag.T_OT;
    if (T_CT.translation().z() <= 0.0 || T_CT.linear().col(2).dot(T_CT.translation()) >= 0.0) continue;  // behind, or seen from the back
    Eigen::AlignedBox2d box;
    bool in_front = true;
    for (const Vec3& c : tag.CornersO()) {
      const Vec3 X = T_CO * c;
      in_front = in_front && X.z() > 1e-3;
      if (in_front) box.extend(K.Project(X));
    }
    if (!in_front) continue;
    const double margin = std::max(40.0, box.sizes().maxCoeff());
    const PixelRect region{static_cast<int>(std::floor(box.min().x() - margin)), static_cast<int>(std::floor(box.min().y() - margin)),
                           static_cast<int>(std::ceil(box.max().x() + margin)), static_cast<int>(std::ceil(box.max().y() + margin))};
    for (const TagDetection& d : tag_detector_fine_->Detect(state_.image, region))
      if (d.id == tag.id) state_.tags.push_back(d);
  }
}

namespace {

// The scene as a filter believes it (hand at its biased joints, object at its estimate), seen
// from the camera: the virtual image of the feature step and of the replay's middle view.
Scene BelievedScene(const Filter& f, const Transform& T_PC, const Intrinsics& K, const HandMeshes& hand,
                    const std::vector<int>& object, const Vec3& background) {
  Scene scene;
  scene.K = K;
  scene.T_PC = T_PC;
  scene.background = background;
  AddHand(scene, hand, f.kinematics().link_poses());
  AddObject(scene, object, f.T_PO());
  return scene;
}

}  // namespace

void Pipeline::FeatureUpdate(std::size_t set, int frame) {
  Filter& f = *filters_[set];
  const Intrinsics& K = *session_.info().camera;
  const CameraFrame& cf = session_.camera_frames()[static_cast<std::size_t>(frame)];
  const auto start = std::chrono::steady_clock::now();
  // The virtual image: the scene as this filter believes it, from the camera.
  FeatureStep& fs = state_.feature_step;
  fs.frame = frame;
  renderer_->Render(BelievedScene(f, cf.T_PC, K, hand_meshes_, object_meshes_, Vec3(0.5, 0.5, 0.5)), fs.virtual_view, true);
  std::vector<std::uint8_t> mask(fs.virtual_view.label.size()), hand(mask.size());
  for (std::size_t i = 0; i < mask.size(); ++i) {
    mask[i] = fs.virtual_view.label[i] == kObjectLabel;
    hand[i] = fs.virtual_view.label[i] >= kHandLabelBase && fs.virtual_view.label[i] < kExtraLabelBase;
  }
  fs.match = MatchFeatures(state_.image, fs.virtual_view.colour, &mask, feature_params_, &hand);
  // Inliers to object points through the virtual depth, moved into O with the estimate.
  const Transform T_OP = f.T_PO().inverse();
  state_.features.clear();
  fs.used_match.clear();
  for (std::size_t m = 0; m < fs.match.matches.size(); ++m) {
    const FeatureMatch& match = fs.match.matches[m];
    if (!match.inlier) continue;
    const int x = static_cast<int>(std::lround(match.virtual_px.x())), y = static_cast<int>(std::lround(match.virtual_px.y()));
    if (x < 0 || y < 0 || x >= K.width || y >= K.height || !mask[std::size_t(y) * K.width + x]) continue;
    const float z = fs.virtual_view.depth_at(x, y);
    if (!std::isfinite(z)) continue;
    const Vec3 X_P = cf.T_PC * K.Unproject(match.virtual_px, z);
    state_.features.push_back({match.id, T_OP * X_P, K.Undistort(match.real_px)});
    fs.used_match.push_back(static_cast<int>(m));
  }
  const Transform T_CP = cf.T_PC.inverse();
  const auto residuals = [&](std::vector<double>& out) {
    const Transform T_PO = f.T_PO();
    out.clear();
    for (const VisualFeature& v : state_.features) out.push_back((K.Project(T_CP * (T_PO * v.x_O)) - v.pixel).norm());
  };
  residuals(fs.residual_before);
  state_.last[set].visual_used = f.UpdateVisual(state_.features, cf.T_PC, K);
  state_.last[set].gated += f.trace().num_gated;
  double m2 = 0.0;
  for (const FilterTrace::Visual& v : f.trace().visual) m2 += v.mahalanobis;
  state_.last[set].visual_mahalanobis = f.trace().visual.empty() ? 0.0 : m2 / static_cast<double>(f.trace().visual.size());
  residuals(fs.residual_after);
  state_.last[set].visual_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  state_.last[set].T_PO = f.T_PO();
}

namespace {

OverlayContact::Kind Kind(ContactKind k) {
  switch (k) {
    case ContactKind::kKinematic: return OverlayContact::Kind::kKinematic;
    case ContactKind::kTorque: return OverlayContact::Kind::kTorque;
    case ContactKind::kRejectedCone:
    case ContactKind::kRejectedForce: return OverlayContact::Kind::kRejected;
    case ContactKind::kCandidate: break;
  }
  return OverlayContact::Kind::kCandidate;
}

}  // namespace

FrameComposer::FrameComposer(const Pipeline& pipeline) : p_(pipeline) {
  hand_meshes_ = UploadHand(renderer_, p_.models().hand);
  object_meshes_ = UploadObject(renderer_, p_.models().object, PrintedTagMeshes(p_.models().object));
  painter_ = std::make_unique<OverlayPainter>(renderer_, object_meshes_);
}

Image8 FrameComposer::Compose(int camera_frame, double t, const OverlayLayers& layers) {
  const Session& s = p_.session();
  const CameraFrame& frame = s.camera_frames().at(static_cast<std::size_t>(camera_frame));
  const Intrinsics& K = *s.info().camera;
  OverlayFrame of;
  of.camera = p_.last_frame() == camera_frame ? p_.last_image() : s.LoadImage(camera_frame);
  of.T_PC = frame.T_PC;
  of.K = K;
  of.friction_cone_deg = p_.params().friction_cone_deg;
  std::ostringstream hud;
  hud << std::fixed << std::setprecision(3) << "t = " << t << " s   frame " << camera_frame;
  of.hud.push_back(hud.str());
  if (s.has_groundtruth())
    of.estimates.push_back({"truth", kColourTruth, s.GroundTruthAt(t), Mat3::Zero(), true, {}, {}});
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    const Filter& f = p_.filter(i);
    const EstimateRecord& r = p_.last(i);
    OverlayEstimate e{p_.sets()[i].name, p_.sets()[i].colour, r.T_PO, f.covariance().topLeftCorner<3, 3>(), false, {}, {}};
    for (const FilterTrace::Contact& c : f.trace().contacts)
      e.contacts.push_back({Kind(c.kind), c.c_o_P, c.c_f_P, c.normal_P, c.force_P});
    for (const FilterTrace::Visual& v : f.trace().visual) e.features.push_back({v.measured, v.predicted, !v.gated});
    of.estimates.push_back(e);
    std::ostringstream line;
    line << std::fixed << std::setprecision(1) << p_.sets()[i].name << ": ";
    if (std::isfinite(r.position_error))
      line << r.position_error * 1000 << " mm / " << r.orientation_error * 180 / M_PI << " deg, ";
    line << r.constraints << " constraints";
    of.hud.push_back(line.str());
  }
  const Image8 annotated = painter_->Paint(of, layers);

  // The virtual view: the scene as the last set believes it, from the camera.
  const std::size_t last = p_.sets().size() - 1;
  const Filter& f = p_.filter(last);
  RenderOutput virtual_out;
  renderer_.Render(BelievedScene(f, frame.T_PC, K, hand_meshes_, object_meshes_, Vec3(0.12, 0.12, 0.14)), virtual_out, false);

  // External 3-D view around the palm: estimates translucent in their colours, truth opaque.
  Scene outside;
  outside.K = K;
  outside.background = Vec3(0.93, 0.94, 0.96);
  const Aabb box = p_.models().object.Bounds();
  const Vec3 centre = p_.last(last).T_PO * box.Center();
  outside.T_PC = OrbitCamera(0.5 * centre + Vec3(0, 0.025, 0.0), orbit.distance, orbit.azimuth, orbit.elevation, Vec3::UnitY());
  AddHand(outside, hand_meshes_, f.kinematics().link_poses(), 1.0);
  if (s.has_groundtruth()) {
    ObjectStyle truth;
    truth.rgba = Eigen::Vector4d(0.15, 0.15, 0.15, 1.0);
    AddObject(outside, object_meshes_, s.GroundTruthAt(t), truth);
  }
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    ObjectStyle style;
    const Rgb& c = p_.sets()[i].colour;
    style.rgba = Eigen::Vector4d(c.r / 255.0, c.g / 255.0, c.b / 255.0, 0.45);
    AddObject(outside, object_meshes_, p_.last(i).T_PO, style);
  }
  RenderOutput orbit_out;
  renderer_.Render(outside, orbit_out, false);
  return SideBySide({&annotated, &virtual_out.colour, &orbit_out.colour},
                    {"camera + estimates (truth dashed)", "virtual view at " + p_.sets()[last].name + " estimate",
                     "3-D view: truth dark, estimates translucent"});
}

}  // namespace inhand::app
