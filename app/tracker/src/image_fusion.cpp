#include "image_fusion.hpp"

#include <algorithm>
#include <chrono>

#include "extracted_features.hpp"
#include "history.hpp"
#include "tag_source.hpp"

namespace inhand {

VisualUpdate VisualUpdate::Features(double t_capture, const Transform& T_PC, const Intrinsics& K,
                                    double widen_position, std::vector<VisualFeature> features) {
  VisualUpdate u;
  u.t_capture = t_capture;
  u.widen_position = widen_position;
  u.features = std::move(features);
  u.T_PC = T_PC;
  u.K = K;
  return u;
}

VisualUpdate VisualUpdate::Relocation(double t_capture, const Transform& T_PO,
                                      const Mat6& covariance, const Transform& T_PC,
                                      const Intrinsics& K) {
  VisualUpdate u = Features(t_capture, T_PC, K);
  u.relocate = true;
  u.relocate_T_PO = T_PO;
  u.relocate_covariance = covariance;
  return u;
}

namespace tracker_detail {

FilterOptions FilterOptionsFor(const ObjectModel& object, const Modalities& m) {
  FilterOptions options;
  options.use_torque = m.torque;
  options.gyration_O = object.inertia_com / object.mass;  // for FilterParams::travel_orientation
  options.symmetry_axis_O = object.symmetry_axis_O;
  options.symmetry_point_O = object.symmetry_point_O;
  return options;
}

ImageFusion::ImageFusion(const HandModel& hand, const ObjectModel& object, const Modalities& m,
                         const TrackerParams& params, Filter* shared) {
  if (shared) {
    filter_ = shared;
  } else {
    query_ = std::make_unique<BulletContactQuery>(hand, object);
    own_ = std::make_unique<Filter>(hand, *query_, params.filter, FilterOptionsFor(object, m));
    filter_ = own_.get();
  }
  if (m.features)
    sources_.push_back(std::make_unique<ExtractedFeatures>(hand, object, params, m.torque));
  if (m.tags) sources_.push_back(std::make_unique<TagSource>(object, params));
}

ImageFusion::~ImageFusion() = default;

int ImageFusion::Apply(const VisualUpdate& u, double& m2) {
  Filter& f = *filter_;
  if (u.relocate) {
    f.Relocate(u.relocate_T_PO, u.relocate_covariance);
    return 0;
  }
  if (u.widen_position > 0.0) f.WidenPose(u.widen_position, 0.0);
  const int used = f.UpdateVisual(u.features, u.T_PC, u.K);
  step_.used += used;
  step_.offered += static_cast<int>(u.features.size());
  const auto& visual = f.trace().visual;
  // How far this update's measurements put the object from the estimate before it (VisualStep::
  // displacement): each residual at its point's depth, from the filter's own projections.
  displacements_.clear();
  for (std::size_t i = visual.size() - u.features.size(); i < visual.size(); ++i) {
    const FilterTrace::Visual& v = visual[i];
    m2 += v.mahalanobis;
    if (v.depth > 1e-3)
      displacements_.push_back((v.measured - v.predicted).norm() * v.depth / u.K.fx);
  }
  if (!displacements_.empty()) {
    const auto mid = displacements_.begin() + static_cast<long>(displacements_.size() / 2);
    std::nth_element(displacements_.begin(), mid, displacements_.end());
    step_.displacement = std::max(step_.displacement, *mid);
  }
  return used;
}

void ImageFusion::Fuse(double t_c, const Image8& image, const Transform& T_PC, const Intrinsics& K,
                       long last) {
  Filter& f = *filter_;
  const auto start = std::chrono::steady_clock::now();
  f.Restore(slots_[0].after_sample);
  std::vector<VisualUpdate>& here = slots_[0].fused;
  std::size_t split = 0;
  while (split < here.size() && here[split].t_capture <= t_c) History::Apply(f, here[split++]);

  step_.tags.clear();
  step_.has_features = false;
  step_.offered = step_.used = 0;
  step_.relocalized = 0.0;
  step_.recovered = false;
  step_.shifts_refused = 0;
  step_.displacement = 0.0;
  double m2 = 0.0;
  fresh_.clear();
  for (const auto& source : sources_) {
    VisualUpdate u = VisualUpdate::Features(t_c, T_PC, K);
    source->Measure(image, T_PC, K, slots_[0].tau, f, step_, u);
    const int used = Apply(u, m2);
    source->Fused(f, u, used, step_);
    fresh_.push_back(std::move(u));
  }
  step_.mean_mahalanobis = step_.offered > 0 ? m2 / step_.offered : 0.0;
  step_.t_capture = t_c;
  step_.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  here.insert(here.begin() + static_cast<long>(split), fresh_.begin(), fresh_.end());
  for (std::size_t i = split + fresh_.size(); i < here.size(); ++i) History::Apply(f, here[i]);
  Replay(1, last);
}

void ImageFusion::Replay(long from, long to) {
  for (long k = from; k <= to; ++k) History::Replay(*filter_, slots_[static_cast<std::size_t>(k)]);
}

VisualMemory ImageFusion::Memory() const {
  VisualMemory m;
  for (const auto& source : sources_) source->Remember(m);
  return m;
}

void ImageFusion::Recall(const VisualMemory& m) {
  for (const auto& source : sources_) source->Recall(m);
}

}  // namespace tracker_detail
}  // namespace inhand
