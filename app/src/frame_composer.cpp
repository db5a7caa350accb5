#include "inhand/app/frame_composer.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/renderer/printed_tags.hpp"

namespace inhand::app {

namespace {

OverlayContact::Kind Kind(ContactKind k) {
  switch (k) {
    case ContactKind::kKinematic:
      return OverlayContact::Kind::kKinematic;
    case ContactKind::kTorque:
      return OverlayContact::Kind::kTorque;
    case ContactKind::kRejectedCone:
    case ContactKind::kRejectedForce:
      return OverlayContact::Kind::kRejected;
    case ContactKind::kCandidate:
      break;
  }
  return OverlayContact::Kind::kCandidate;
}

}  // namespace

double LargestSigma(const Mat3& covariance) {
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(covariance, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

std::string HudLine(const std::string& name, const PictureState::Set& set) {
  const EstimateRecord& r = set.record;
  std::ostringstream line;
  line << std::fixed << std::setprecision(1) << name << ": ";
  if (std::isfinite(r.position_error))
    line << r.position_error * 1000 << " mm / " << r.orientation_error * 180 / M_PI << " deg, ";
  line << "sigma " << LargestSigma(set.pose_covariance.topLeftCorner<3, 3>()) * 1000 << " mm / "
       << LargestSigma(set.pose_covariance.block<3, 3>(3, 3)) * 180 / M_PI << " deg, ";
  line << r.constraints << (r.constraints == 1 ? " constraint" : " constraints");
  if (set.found_again > 0.0) line << ", found again " << set.found_again * 1000 << " mm away";
  if (r.memory.features_lost())
    line << ", object not matched in " << r.memory.features_poor_frames << " frames";
  if (r.memory.tag_disagreements > 0) line << ", tags see it elsewhere";
  if (r.slipping) line << ", grip loosened";
  if (!set.health.empty()) {
    std::string h = set.health;
    if (r.health.state >= HealthState::kInconsistent)
      for (std::size_t i = 0; i < h.size() && h[i] != ' '; ++i)
        h[i] = static_cast<char>(std::toupper(h[i]));
    line << " -- " << h;
  }
  return line.str();
}

PictureState::Set CaptureSet(const Tracker& tracker, const EstimateRecord& record, double t,
                             const HandModel& hand) {
  const Filter& f = tracker.filter();
  PictureState::Set set;
  set.record = record;
  set.pose_covariance = tracker.claimed_pose_covariance();
  set.contacts = f.trace().contacts;
  set.visual = f.trace().visual;
  const TrackerStats stats = tracker.stats();
  if (stats.relocalizations > 0 && stats.last_relocalization_t <= t &&
      t - stats.last_relocalization_t <= 1.0)
    set.found_again = stats.last_relocalized;
  if (set.record.health.state != HealthState::kOk)
    set.health = HealthMessage(set.record.health, hand);
  return set;
}

OverlayEstimate OverlayOf(const std::string& name, const Rgb& colour, const PictureState::Set& set,
                          int selected_link, int selected_visual) {
  OverlayEstimate e{name, colour, set.record.T_PO, set.pose_covariance.topLeftCorner<3, 3>(), false,
                    {},   {}};
  for (const FilterTrace::Contact& c : set.contacts)
    e.contacts.push_back({Kind(c.kind), c.c_o_P, c.c_f_P, c.normal_P, c.force_P,
                          selected_link >= 0 && c.link == selected_link});
  for (const FilterTrace::Visual& v : set.visual)
    e.features.push_back(
        {v.measured, v.predicted, !v.gated, selected_visual >= 0 && v.id == selected_visual});
  return e;
}

FrameComposer::FrameComposer(const SessionPlayer& player)
    : p_(player), query_(player.models().hand, player.models().object) {
  hand_meshes_ = UploadHand(renderer_, p_.models().hand);
  object_meshes_ =
      UploadObject(renderer_, p_.models().object, PrintedTagMeshes(p_.models().object));
  painter_ = std::make_unique<OverlayPainter>(renderer_, object_meshes_);
}

PictureState FrameComposer::Capture(const SessionPlayer& p, int camera_frame, double t,
                                    bool camera_image) {
  PictureState st;
  st.t = t;
  st.camera_frame = camera_frame;
  if (camera_frame >= 0 && camera_image)
    st.camera = p.last_frame() == camera_frame && !p.last_image().empty()
                    ? p.last_image()
                    : p.session().LoadImage(camera_frame);
  for (std::size_t i = 0; i < p.sets().size(); ++i)
    st.sets.push_back(CaptureSet(p.tracker(i), p.last(i), t, p.models().hand));
  const std::size_t last = p.sets().size() - 1;
  st.link_poses = p.tracker(last).filter().kinematics().link_poses();
  if (camera_frame >= 0 && p.sets()[last].features) {
    const VisualStep& v = p.tracker(last).last_visual();
    const double t_frame = p.session().camera_frames().at(static_cast<std::size_t>(camera_frame)).t;
    if (v.sequence > 0 && v.has_features && v.t_capture == t_frame)
      st.matched_view = v.virtual_view.colour;
  }
  return st;
}

void FrameComposer::AddEstimates(OverlayFrame* of, const PictureState& st) const {
  const Session& s = p_.session();
  if (s.has_groundtruth())
    of->estimates.push_back(
        {"truth", kColourTruth, s.GroundTruthAt(st.t), Mat3::Zero(), true, {}, {}});
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    const PictureState::Set& set = st.sets[i];
    const bool chosen = selection.set == static_cast<int>(i);
    of->estimates.push_back(OverlayOf(p_.sets()[i].name, p_.sets()[i].colour, set,
                                      chosen ? selection.link : -1,
                                      chosen ? selection.visual : -1));
    of->hud.push_back(HudLine(p_.sets()[i].name, set));
  }
}

Scene FrameComposer::ExternalScene(const PictureState& st, const Intrinsics& K,
                                   const Orbit& from) const {
  const Session& s = p_.session();
  Scene outside;
  outside.K = K;
  outside.background = Vec3(0.93, 0.94, 0.96);
  const Aabb box = p_.models().object.Bounds();
  const Vec3 centre = st.sets.back().record.T_PO * box.Center();
  outside.T_PC = OrbitCamera(0.5 * centre + Vec3(0, 0.025, 0.0), from.distance, from.azimuth,
                             from.elevation, Vec3::UnitY());
  AddHand(outside, hand_meshes_, st.link_poses, 1.0, true);
  if (s.has_groundtruth()) {
    ObjectStyle truth;
    truth.rgba = Eigen::Vector4d(0.15, 0.15, 0.15, 1.0);
    AddObject(outside, object_meshes_, s.GroundTruthAt(st.t), truth);
  }
  for (std::size_t i = 0; i < p_.sets().size(); ++i) {
    ObjectStyle style;
    const Rgb& c = p_.sets()[i].colour;
    style.rgba = Eigen::Vector4d(c.r / 255.0, c.g / 255.0, c.b / 255.0, 0.45);
    AddObject(outside, object_meshes_, st.sets[i].record.T_PO, style);
  }
  return outside;
}

std::vector<OverlayGap> FrameComposer::Gaps(const PictureState& st) {
  const HandModel& hand = p_.models().hand;
  query_.Query(st.link_poses, st.sets.back().record.T_PO, 0.05, pairs_);
  // One per finger (the links after the same first moving joint; the palm on its own).
  std::map<int, const ContactPair*> nearest;
  for (const ContactPair& c : pairs_) {
    const auto& support = hand.support.at(static_cast<std::size_t>(c.link));
    const int finger = support.empty() ? -1 : support.front();
    const ContactPair*& n = nearest[finger];
    if (!n || c.distance < n->distance) n = &c;
  }
  std::vector<OverlayGap> gaps;
  for (const auto& [finger, c] : nearest) gaps.push_back({c->c_f_P, c->c_o_P, c->distance});
  return gaps;
}

void FrameComposer::AddSideView(const PictureState& st, Image8& view) {
  // A third of the width, the orbit turned by 90° about the vertical, level.
  Orbit side = orbit;
  side.azimuth -= M_PI / 2;
  side.elevation = 0.1;
  side.distance *= 0.8;
  const int w = view.width / 3 / 2 * 2, h = w * 3 / 4;
  RenderOutput small;
  renderer_.Render(ExternalScene(st, IntrinsicsFromFov(w, h, 40.0), side), small, false);
  Inset(view, small.colour, "side view");
}

Image8 FrameComposer::Compose(const PictureState& st, const OverlayLayers& layers) {
  const Session& s = p_.session();
  INHAND_CHECK(st.camera_frame >= 0 && !st.camera.empty(),
               "FrameComposer::Compose without a camera frame");
  const CameraFrame& frame = s.camera_frames().at(static_cast<std::size_t>(st.camera_frame));
  const Intrinsics& K = *s.info().camera;
  OverlayFrame of;
  of.camera = st.camera;
  of.T_PC = frame.T_PC;
  of.K = K;
  of.friction_cone_deg = p_.params().filter.friction_cone_deg;
  std::ostringstream hud;
  hud << std::fixed << std::setprecision(3) << "t = " << st.t << " s   frame " << st.camera_frame;
  of.hud.push_back(hud.str());
  AddEstimates(&of, st);
  const Image8 annotated = painter_->Paint(of, layers);

  // The virtual view: the scene as the last set believes it, from the camera; when it matched
  // features on this frame, the very image it matched them against (drawn only around the
  // object: VisualStep::region).
  const std::size_t last = p_.sets().size() - 1;
  RenderOutput virtual_out;
  const Image8* middle = &st.matched_view;
  std::string virtual_caption = "virtual view " + p_.sets()[last].name +
                                " matched (before the update; drawn near the object)";
  if (middle->empty()) {
    renderer_.Render(CameraScene(hand_meshes_, st.link_poses, object_meshes_,
                                 st.sets.back().record.T_PO, frame.T_PC, K, Vec3(0.12, 0.12, 0.14)),
                     virtual_out, false);
    middle = &virtual_out.colour;
    virtual_caption = "virtual view at " + p_.sets()[last].name + " estimate";
  }

  // External 3-D view around the palm: estimates translucent in their colours, truth opaque.
  RenderOutput orbit_out;
  const Scene outside = ExternalScene(st, K, orbit);
  renderer_.Render(outside, orbit_out, false);
  OverlayFrame cues;
  cues.camera = std::move(orbit_out.colour);
  cues.T_PC = outside.T_PC;
  cues.K = outside.K;
  cues.gaps = Gaps(st);
  // Of the contacts, the inspector's selection alone (its markers, ringed): the rest would hide
  // the gaps.
  if (selection.link >= 0 && selection.set >= 0 &&
      static_cast<std::size_t>(selection.set) < st.sets.size()) {
    const std::size_t i = static_cast<std::size_t>(selection.set);
    OverlayEstimate chosen =
        OverlayOf(p_.sets()[i].name, p_.sets()[i].colour, st.sets[i], selection.link, -1);
    chosen.contacts.erase(std::remove_if(chosen.contacts.begin(), chosen.contacts.end(),
                                         [](const OverlayContact& c) { return !c.selected; }),
                          chosen.contacts.end());
    chosen.features.clear();
    cues.estimates.push_back(std::move(chosen));
  }
  OverlayLayers only_gaps;
  only_gaps.silhouette = only_gaps.outline = only_gaps.forces = false;
  only_gaps.cones = only_gaps.features = only_gaps.axes = only_gaps.uncertainty = false;
  only_gaps.hud = false;
  Image8 external = painter_->Paint(cues, only_gaps);
  AddSideView(st, external);
  const bool truth = s.has_groundtruth();
  const std::string camera_caption =
      truth ? "camera + estimates (truth dashed)" : "camera + estimates (no ground truth)";
  const std::string external_caption =
      std::string(truth ? "3-D view: truth dark, estimates translucent"
                        : "3-D view: estimates translucent") +
      ", finger gaps to " + p_.sets()[last].name;
  if (layout == Layout::kCameraLarge) {
    // MainAndColumn scales the column's panels to half the camera's height.
    const int half = annotated.height / 2;
    const double scale = static_cast<double>(half) / external.height;
    external_view_ = {true,      outside.T_PC,
                      outside.K, annotated.width,
                      half,      static_cast<int>(std::lround(external.width * scale)),
                      half,      scale};
    return MainAndColumn(annotated, {middle, &external},
                         {camera_caption, virtual_caption, external_caption});
  }
  // SideBySide scales every panel to the camera's height.
  const double to_height = static_cast<double>(annotated.height);
  const int x0 =
      annotated.width + static_cast<int>(std::lround(middle->width * to_height / middle->height));
  const double scale = to_height / external.height;
  external_view_ = {true,
                    outside.T_PC,
                    outside.K,
                    x0,
                    0,
                    static_cast<int>(std::lround(external.width * scale)),
                    annotated.height,
                    scale};
  return SideBySide({&annotated, middle, &external},
                    {camera_caption, virtual_caption, external_caption});
}

Image8 FrameComposer::ComposeExternal(const PictureState& st, int width, int height,
                                      const OverlayLayers& layers) {
  const Scene scene = ExternalScene(st, IntrinsicsFromFov(width, height, 40.0), orbit);
  external_view_ = {true, scene.T_PC, scene.K, 0, 0, width, height, 1.0};
  RenderOutput out;
  renderer_.Render(scene, out, false);
  OverlayFrame of;
  of.camera = std::move(out.colour);
  of.T_PC = scene.T_PC;
  of.K = scene.K;
  of.friction_cone_deg = p_.params().filter.friction_cone_deg;
  std::ostringstream hud;
  hud << std::fixed << std::setprecision(3) << "t = " << st.t << " s   3-D view (no camera): "
      << (p_.session().has_groundtruth() ? "truth dark, estimates translucent"
                                         : "estimates translucent, no ground truth")
      << ", finger gaps to " << p_.sets().back().name;
  of.hud.push_back(hud.str());
  AddEstimates(&of, st);
  // The objects are already drawn in 3-D: the overlays add contacts, forces, axes and the HUD.
  of.gaps = Gaps(st);
  OverlayLayers l = layers;
  l.silhouette = l.outline = l.features = false;
  Image8 view = painter_->Paint(of, l);
  AddSideView(st, view);
  return view;
}

}  // namespace inhand::app
