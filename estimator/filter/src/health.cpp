#include "inhand/filter/health.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "inhand/core/error.hpp"
#include "inhand/filter/filter.hpp"

namespace inhand {

const char* HealthStateName(HealthState state) {
  switch (state) {
    case HealthState::kOk:
      return "ok";
    case HealthState::kUncertain:
      return "uncertain";
    case HealthState::kInconsistent:
      return "inconsistent";
    case HealthState::kLost:
      return "lost";
  }
  return "?";
}

const char* HealthCauseName(HealthCause cause) {
  switch (cause) {
    case HealthCause::kNone:
      return "none";
    case HealthCause::kWideSigma:
      return "wide_sigma";
    case HealthCause::kSlipping:
      return "slipping";
    case HealthCause::kRelocalized:
      return "relocalized";
    case HealthCause::kFeaturesLost:
      return "features_lost";
    case HealthCause::kImagesStale:
      return "images_stale";
    case HealthCause::kImagesFrozen:
      return "images_frozen";
    case HealthCause::kVisionDisagrees:
      return "vision_disagrees";
    case HealthCause::kVisionBlind:
      return "vision_blind";
    case HealthCause::kTagsElsewhere:
      return "tags_elsewhere";
    case HealthCause::kPenetration:
      return "penetration";
    case HealthCause::kPressingInAir:
      return "pressing_in_air";
  }
  return "?";
}

double HealthPositionSigma(const Health& h) {
  if (h.state != HealthState::kInconsistent && h.state != HealthState::kLost) return 0.0;
  return std::isfinite(h.distance) ? std::abs(h.distance) : 0.0;
}

Mat6 ClaimedPoseCovariance(const Mat6& P, const Health& health, const Mat3& R_PO,
                           const Mat3& gyration_O) {
  const double s = HealthPositionSigma(health);
  Mat6 claimed = P;
  if (s <= 0.0) return claimed;
  claimed.topLeftCorner<3, 3>().diagonal().array() += s * s;
  if (gyration_O.isZero(0.0)) return claimed;
  constexpr double kUniform = M_PI * M_PI / 3.0;  // the variance of an angle uniform on a circle
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (gyration_O + gyration_O.transpose()));
  Vec3 turn;
  for (int i = 0; i < 3; ++i) {
    const double g = eig.eigenvalues()[i];
    turn[i] = g > 0.0 ? std::min(s * s / g, kUniform) : kUniform;
  }
  const Mat3 V = R_PO * eig.eigenvectors();
  const Mat3 C = V * turn.asDiagonal() * V.transpose();
  claimed.bottomRightCorner<3, 3>() += 0.5 * (C + C.transpose());  // exactly symmetric
  return claimed;
}

std::string HealthMessage(const Health& h, const HandModel& hand) {
  const std::string link = h.subject >= 0 && h.subject < static_cast<int>(hand.links.size())
                               ? hand.links[static_cast<std::size_t>(h.subject)].name
                               : std::string("a link");
  char what[200];
  switch (h.cause) {
    case HealthCause::kNone:
      std::snprintf(what, sizeof what, "every check passes");
      break;
    case HealthCause::kWideSigma:
      if (h.subject == 1)
        std::snprintf(what, sizeof what, "orientation sigma %.1f deg", h.value * 180 / M_PI);
      else
        std::snprintf(what, sizeof what, "position sigma %.1f mm", h.value * 1000);
      break;
    case HealthCause::kSlipping:
      std::snprintf(what, sizeof what, "the grip loosened: the object may slip");
      break;
    case HealthCause::kRelocalized:
      std::snprintf(what, sizeof what, "the object was found again %.1f mm away", h.value * 1000);
      break;
    case HealthCause::kFeaturesLost:
      std::snprintf(what, sizeof what, "the image features are lost");
      break;
    case HealthCause::kImagesStale:
      std::snprintf(what, sizeof what, "no new image for %.2f s", h.value);
      break;
    case HealthCause::kImagesFrozen:
      std::snprintf(what, sizeof what, "%d identical images in a row", static_cast<int>(h.value));
      break;
    case HealthCause::kVisionDisagrees:
      std::snprintf(what, sizeof what, "the estimate's gate refuses %.0f%% of the image features",
                    h.value * 100);
      break;
    case HealthCause::kVisionBlind:
      std::snprintf(what, sizeof what,
                    "the last images fused %d point%s of the object, too few to check the estimate",
                    static_cast<int>(h.value), static_cast<int>(h.value) == 1 ? "" : "s");
      break;
    case HealthCause::kTagsElsewhere:
      std::snprintf(what, sizeof what, "the tags see the object elsewhere");
      break;
    case HealthCause::kPenetration:
      std::snprintf(what, sizeof what, "%s is %.1f mm inside the object", link.c_str(),
                    h.value * 1000);
      break;
    case HealthCause::kPressingInAir:
      std::snprintf(what, sizeof what, "%s presses but the object is %.1f mm from it", link.c_str(),
                    h.value * 1000);
      break;
  }
  char line[260];
  std::snprintf(line, sizeof line, "%s since %.2f s: %s", HealthStateName(h.state), h.since, what);
  return line;
}

void HealthParams::Validate(const std::string& source) const {
  const auto positive = [&](double v, const char* name, double hi) {
    if (!(v > 0.0 && v <= hi))
      throw InputError(source + ": parameter 'health." + name + "' is " + std::to_string(v) +
                       ", expected in (0, " + std::to_string(hi) + "]");
  };
  positive(uncertain_position, "uncertain_position", 10.0);
  positive(uncertain_orientation, "uncertain_orientation", 2 * M_PI);
  positive(penetration, "penetration", 1.0);
  positive(press_torque, "press_torque", 1e4);
  positive(press_gap, "press_gap", 1.0);
  positive(press_reach, "press_reach", 1.0);
  positive(press_period, "press_period", 10.0);
  positive(images_stale, "images_stale", 1e4);
  positive(lost_after, "lost_after", 1e4);
  positive(vision_gated_share, "vision_gated_share", 1.0);
  positive(recover_reach, "recover_reach", 1.0);
  if (!(recover_gap >= press_gap && recover_gap < recover_reach))
    throw InputError(source + ": parameter 'health.recover_gap' is " + std::to_string(recover_gap) +
                     ", expected >= 'health.press_gap' and < 'health.recover_reach'");
  if (recover_images < 0 || recover_images > 1000)
    throw InputError(source + ": parameter 'health.recover_images' is " +
                     std::to_string(recover_images) + ", expected in [0, 1000]");
  if (!(press_reach >= press_gap))
    throw InputError(source + ": parameter 'health.press_reach' must be >= 'health.press_gap'");
  for (const auto& [v, name] : {std::pair{sustain, "sustain"},
                                {relocalized_hold, "relocalized_hold"},
                                {slip_hold, "slip_hold"}})
    if (!(v >= 0.0 && v <= 1e4))
      throw InputError(source + ": parameter 'health." + name + "' is " + std::to_string(v) +
                       ", expected in [0, 1e4] s");
  if (vision_window < 1 || vision_window > 32 || vision_min_offered < 1 || vision_min_used < 0 ||
      images_frozen < 2)
    throw InputError(source +
                     ": parameter 'health.vision_window' must be in [1, 32], "
                     "'health.vision_min_offered' >= 1, 'health.vision_min_used' >= 0 and "
                     "'health.images_frozen' >= 2");
}

// --- the press check

PressCheck::PressCheck(const HandModel& hand) : fingers_(hand) {
  const std::size_t links = hand.links.size();
  torque_.assign(fingers_.finger_q.size(), 0.0);
  gap_.assign(fingers_.finger_q.size(), 0.0);
  nearest_.assign(fingers_.finger_q.size(), -1);
  pairs_.reserve(2 * links + 8);
}

PressEvidence PressCheck::Measure(const Eigen::Ref<const Eigen::VectorXd>& tau,
                                  const std::vector<Transform>& T_PL, const Transform& T_PO,
                                  const FilterTrace& trace, ContactQuery& query,
                                  const HealthParams& params) {
  PressEvidence out;
  if (!tau.allFinite()) return out;
  bool any = false, query_needed = false;
  for (std::size_t f = 0; f < fingers_.finger_q.size(); ++f) {
    const double t = fingers_.Torque(static_cast<int>(f), tau);
    torque_[f] = t;
    gap_[f] = params.press_reach;
    nearest_[f] = -1;
    if (t >= params.press_torque) any = true;
  }
  if (!any) return out;
  // The step's own contacts first: a pressing finger with a link within its reach is close.
  for (const FilterTrace::Contact& c : trace.contacts) {
    if (c.iteration != 0 || c.link < 0) continue;
    const int f = fingers_.link_finger[static_cast<std::size_t>(c.link)];
    if (f >= 0 && c.distance < gap_[static_cast<std::size_t>(f)])
      gap_[static_cast<std::size_t>(f)] = c.distance,
      nearest_[static_cast<std::size_t>(f)] = c.link;
  }
  for (std::size_t f = 0; f < fingers_.finger_q.size(); ++f)
    query_needed = query_needed || (torque_[f] >= params.press_torque && nearest_[f] < 0);
  if (query_needed) {
    query.Query(T_PL, T_PO, params.press_reach, pairs_);
    for (const ContactPair& p : pairs_) {
      const int f = fingers_.link_finger[static_cast<std::size_t>(p.link)];
      if (f >= 0 && p.distance < gap_[static_cast<std::size_t>(f)])
        gap_[static_cast<std::size_t>(f)] = p.distance,
        nearest_[static_cast<std::size_t>(f)] = p.link;
    }
  }
  for (std::size_t f = 0; f < fingers_.finger_q.size(); ++f) {
    if (torque_[f] < params.press_torque) continue;
    if (!out.pressing || gap_[f] > out.gap) {
      out.pressing = true;
      out.gap = gap_[f];
      out.link = nearest_[f];
      out.torque = torque_[f];
    }
  }
  return out;
}

// --- the monitor

HealthMonitor::HealthMonitor(const HealthParams& params) : params_(params) {}

void HealthMonitor::Reset(double t) {
  const HealthParams p = params_;
  *this = HealthMonitor(p);
  health_.since = t;
}

void HealthMonitor::OnSample(double t, const FilterTrace& trace, const Vec3& sigma_position,
                             const Vec3& sigma_orientation) {
  sigma_position_ = sigma_position;
  sigma_orientation_ = sigma_orientation;
  if (trace.slipping) slipping_t_ = t;
  penetration_ = trace.penetration;
  if (trace.penetration > params_.penetration) {
    if (penetration_since_ < 0.0) penetration_since_ = t;
    double deepest = 0.0;
    for (const FilterTrace::Contact& c : trace.contacts)
      if (-c.distance > deepest) deepest = -c.distance, penetration_link_ = c.link;
  } else {
    penetration_since_ = -1.0;
  }
  Decide(t);
}

void HealthMonitor::OnPress(double t, const PressEvidence& press) {
  press_ = press;
  if (press.pressing && press.gap > params_.press_gap) {
    if (press_since_ < 0.0) press_since_ = t;
  } else {
    press_since_ = -1.0;
  }
}

void HealthMonitor::OnImageAdded(double t_capture, unsigned long long fingerprint) {
  if (have_image_ && fingerprint == last_fingerprint_)
    ++identical_images_;
  else
    identical_images_ = 1;
  have_image_ = true;
  last_fingerprint_ = fingerprint;
  last_image_t_ = std::max(last_image_t_, t_capture);
}

void HealthMonitor::OnImage(const ImageEvidence& image) {
  const int k = images_seen_++ % kMaxWindow;
  offered_[static_cast<std::size_t>(k)] = image.offered;
  used_[static_cast<std::size_t>(k)] = image.used;
  displacement_[static_cast<std::size_t>(k)] = image.displacement;
  features_lost_ = image.features_lost;
  tags_elsewhere_ = image.tags_elsewhere;
  if (image.relocalized > 0.0) relocalized_ = image.relocalized, relocalized_t_ = image.t_capture;
}

void HealthMonitor::Decide(double t) {
  Health h;
  const auto worse = [&](HealthState s, HealthCause c, double v, int subject,
                         double distance = 0.0) {
    if (static_cast<int>(s) > static_cast<int>(h.state))
      h.state = s, h.cause = c, h.value = v, h.subject = subject, h.distance = distance;
  };
  // Inconsistent: the measurements contradict the estimate.
  if (penetration_since_ >= 0.0 && t - penetration_since_ >= params_.sustain)
    worse(HealthState::kInconsistent, HealthCause::kPenetration, penetration_, penetration_link_,
          penetration_);
  if (press_since_ >= 0.0 && t - press_since_ >= params_.sustain)
    worse(HealthState::kInconsistent, HealthCause::kPressingInAir, press_.gap, press_.link,
          press_.gap);
  if (tags_elsewhere_) worse(HealthState::kInconsistent, HealthCause::kTagsElsewhere, 0.0, -1);
  int fused = -1;  // over a full vision window; -1 before one has been seen
  {
    const int n = std::min(images_seen_, params_.vision_window);
    int offered = 0, used = 0, measured = 0;
    double displacement = 0.0;  // the mean over the window's images that measured anything
    for (int i = 1; i <= n; ++i) {
      const std::size_t k = static_cast<std::size_t>((images_seen_ - i) % kMaxWindow);
      offered += offered_[k];
      used += used_[k];
      if (offered_[k] > 0) displacement += displacement_[k], ++measured;
    }
    if (n == params_.vision_window) fused = used;
    const double gated = offered > 0 ? 1.0 - double(used) / offered : 0.0;
    if (offered >= params_.vision_min_offered && gated > params_.vision_gated_share)
      worse(HealthState::kInconsistent, HealthCause::kVisionDisagrees, gated, -1,
            measured > 0 ? displacement / measured : 0.0);
  }
  // Uncertain: the estimate may be off by more than it can use, and says so.
  if (features_lost_) worse(HealthState::kUncertain, HealthCause::kFeaturesLost, 0.0, -1);
  if (have_image_ && identical_images_ >= params_.images_frozen)
    worse(HealthState::kUncertain, HealthCause::kImagesFrozen, identical_images_, -1);
  if (have_image_ && t - last_image_t_ > params_.images_stale)
    worse(HealthState::kUncertain, HealthCause::kImagesStale, t - last_image_t_, -1);
  if (relocalized_t_ >= 0.0 && t - relocalized_t_ <= params_.relocalized_hold)
    worse(HealthState::kUncertain, HealthCause::kRelocalized, relocalized_, -1);
  if (slipping_t_ >= 0.0 && t - slipping_t_ <= params_.slip_hold)
    worse(HealthState::kUncertain, HealthCause::kSlipping, 0.0, -1);
  if (fused >= 0 && fused < params_.vision_min_used)
    worse(HealthState::kUncertain, HealthCause::kVisionBlind, fused, -1);
  const double sp = sigma_position_.maxCoeff(), so = sigma_orientation_.maxCoeff();
  if (sp > params_.uncertain_position)
    worse(HealthState::kUncertain, HealthCause::kWideSigma, sp, 0);
  else if (so > params_.uncertain_orientation)
    worse(HealthState::kUncertain, HealthCause::kWideSigma, so, 1);
  // Lost: inconsistent for too long.
  if (h.state == HealthState::kInconsistent) {
    if (inconsistent_since_ < 0.0) inconsistent_since_ = t;
    if (t - inconsistent_since_ >= params_.lost_after) h.state = HealthState::kLost;
  } else {
    inconsistent_since_ = -1.0;
  }
  h.since = h.state == health_.state ? health_.since : t;
  health_ = h;
}

unsigned long long ImageFingerprint(const unsigned char* data, std::size_t size) {
  const std::size_t stride = (size / 65536) | 1;  // odd: not in step with the channels
  unsigned long long h = 1469598103934665603ull ^ size;
  for (std::size_t i = 0; i < size; i += stride) h = (h ^ data[i]) * 1099511628211ull;
  return h;
}

}  // namespace inhand
