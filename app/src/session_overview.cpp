#include "inhand/app/session_overview.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <utility>

namespace inhand::app {

namespace {

using Set = SessionOverview::Set;

// Every per-sample series of a set: the reader's copy and the publication both go over these.
constexpr std::vector<float> Set::*kSeries[] = {&Set::position_error,
                                                &Set::orientation_error,
                                                &Set::sigma_position,
                                                &Set::sigma_orientation,
                                                &Set::nees,
                                                &Set::penetration,
                                                &Set::constraints,
                                                &Set::gated,
                                                &Set::visual_mahalanobis,
                                                &Set::unexplained_torque,
                                                &Set::contact_mahalanobis,
                                                &Set::contact_force};

// The same for the per-axis series, each axis a series.
constexpr std::array<std::vector<float>, 3> Set::*kAxisSeries[] = {
    &Set::position_error_axis, &Set::orientation_error_axis, &Set::sigma_position_axis,
    &Set::sigma_orientation_axis};

// Calls f(from's series, to's series) for every per-sample series of a set — the plain ones, each
// axis's, each joint's (to's per-joint lists sized to from's first). From is const when reading,
// not when publishing (what is published is cleared).
// Of the per-link series, link `link`'s only (SessionOverview::kAllLinks: every link's); to's other
// links are left empty.
template <typename From, typename F>
void ForEachSeries(From& from, Set& to, F f, int link = SessionOverview::kAllLinks) {
  for (auto series : kSeries) f(from.*series, to.*series);
  for (auto series : kAxisSeries)
    for (std::size_t a = 0; a < 3; ++a) f((from.*series)[a], (to.*series)[a]);
  for (auto series : {&Set::bias, &Set::sigma_bias}) {
    (to.*series).resize((from.*series).size());
    for (std::size_t j = 0; j < (from.*series).size(); ++j) f((from.*series)[j], (to.*series)[j]);
  }
  const auto per_link = [&](auto series) {
    (to.*series).resize((from.*series).size());
    for (std::size_t l = 0; l < (from.*series).size(); ++l) {
      if (link == SessionOverview::kAllLinks || static_cast<int>(l) == link)
        f((from.*series)[l], (to.*series)[l]);
      else
        (to.*series)[l].clear();
    }
  };
  per_link(&Set::link_distance);
  per_link(&Set::link_force);
  per_link(&Set::link_mahalanobis);
  per_link(&Set::link_status);
}

template <typename T>
void AppendFrom(const std::vector<T>& from, std::vector<T>& to, std::size_t have) {
  if (from.size() > have) to.insert(to.end(), from.begin() + static_cast<long>(have), from.end());
}

ContactStatus StatusOf(const FilterTrace::Contact& c) {
  switch (c.kind) {
    case ContactKind::kKinematic:
      return c.gated ? ContactStatus::kGated : ContactStatus::kKinematic;
    case ContactKind::kTorque:
      return c.gated ? ContactStatus::kGated : ContactStatus::kTorque;
    case ContactKind::kRejectedCone:
    case ContactKind::kRejectedForce:
      return ContactStatus::kRejected;
    case ContactKind::kCandidate:
      return ContactStatus::kCandidate;
  }
  return ContactStatus::kNone;
}

}  // namespace

const char* ContactStatusName(ContactStatus status) {
  switch (status) {
    case ContactStatus::kNone:
      return "none";
    case ContactStatus::kCandidate:
      return "candidate";
    case ContactStatus::kRejected:
      return "rejected";
    case ContactStatus::kKinematic:
      return "kinematic";
    case ContactStatus::kTorque:
      return "torque";
    case ContactStatus::kGated:
      return "gated";
  }
  return "?";
}

void LinkContacts(const FilterTrace& trace, std::size_t num_links, std::vector<LinkContact>& out) {
  out.assign(num_links, LinkContact{});
  for (const FilterTrace::Contact& c : trace.contacts) {
    if (c.link < 0 || static_cast<std::size_t>(c.link) >= num_links) continue;
    LinkContact& l = out[static_cast<std::size_t>(c.link)];
    const ContactStatus s = StatusOf(c);
    if (!(c.distance >= l.distance)) l.distance = c.distance;  // NaN at first
    if (s > l.status) l.status = s;                            // the enum is in that order
    if (std::isnan(l.force)) l.force = 0.0;
    if (c.kind == ContactKind::kTorque && !c.gated) l.force += c.force_P.norm();
    const bool constraint = c.kind == ContactKind::kKinematic || c.kind == ContactKind::kTorque;
    if (constraint && !(c.mahalanobis <= l.mahalanobis)) l.mahalanobis = c.mahalanobis;
  }
}

SessionOverview::SessionOverview(const Session& session, const TrackerParams& params,
                                 std::vector<ModalitySet> sets) {
  data_.sets.resize(sets.size());
  thread_ = std::thread(
      [this, &session, params, s = std::move(sets)]() mutable { Run(session, params, s); });
}

SessionOverview::~SessionOverview() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void SessionOverview::Wait() {
  if (thread_.joinable()) thread_.join();
}

long SessionOverview::Read(long version, Data& data, int link) const {
  std::lock_guard<std::mutex> lock(mutex_);
  data.progress = data_.progress;
  if (version == version_) return version;
  if (version < 0) data.t.clear(), data.sets.clear();
  const std::size_t have = data.t.size();
  // The whole session's length at once: a copy grown by doubling would hold up to twice its
  // samples (a 10-minute session's series are hundreds of MB).
  const std::size_t n = samples_;
  data.t.reserve(n);
  AppendFrom(data_.t, data.t, have);
  data.sets.resize(data_.sets.size());
  for (std::size_t i = 0; i < data_.sets.size(); ++i) {
    const Set& from = data_.sets[i];
    Set& to = data.sets[i];
    AppendFrom(from.events, to.events, to.events.size());
    AppendFrom(from.visual, to.visual, to.visual.size());
    ForEachSeries(
        from, to,
        [have, n](const auto& source, auto& target) {
          target.reserve(n);
          if (target.size() < have)  // a link not read before
            target.assign(source.begin(), source.end());
          else
            AppendFrom(source, target, have);
        },
        link);
  }
  return version_;
}

int SessionOverview::CheckpointsReach() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (data_.progress.done) return std::numeric_limits<int>::max();
  return checkpoints_.empty() ? -1 : checkpoints_.rbegin()->first;
}

bool SessionOverview::CheckpointIn(int after, int at_most, int& resume,
                                   SessionPlayer::Checkpoint& checkpoint, int& last_frame) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = checkpoints_.upper_bound(at_most);
  if (it == checkpoints_.begin()) return false;
  --it;
  if (it->first <= after) return false;
  resume = it->first;
  checkpoint = it->second.checkpoint;
  last_frame = it->second.last_frame;
  return true;
}

void SessionOverview::Run(const Session& session, const TrackerParams& params,
                          std::vector<ModalitySet> sets) {
  try {
    SessionPlayer player(session, params, std::move(sets));
    const int n = player.num_samples();
    const std::size_t num_sets = player.sets().size();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      samples_ = static_cast<std::size_t>(n);
      data_.t.reserve(samples_);
    }
    Data found;  // since the last publication
    found.sets.resize(num_sets);
    const auto publish = [&](int k, bool done) {
      std::lock_guard<std::mutex> lock(mutex_);
      data_.t.insert(data_.t.end(), found.t.begin(), found.t.end());
      found.t.clear();
      for (std::size_t i = 0; i < num_sets; ++i) {
        Set& from = found.sets[i];
        Set& to = data_.sets[i];
        to.events.insert(to.events.end(), from.events.begin(), from.events.end());
        from.events.clear();
        to.visual.insert(to.visual.end(), from.visual.begin(), from.visual.end());
        from.visual.clear();
        ForEachSeries(from, to, [n](auto& source, auto& target) {
          target.reserve(static_cast<std::size_t>(n));  // every sample's value, without slack
          target.insert(target.end(), source.begin(), source.end());
          source.clear();
        });
      }
      data_.progress.t = session.t(k);
      data_.progress.share = n > 1 ? static_cast<double>(k) / (n - 1) : 1.0;
      data_.progress.done = done;
      ++version_;
    };
    constexpr int kPublish = 250;  // samples
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    const int spacing = CheckpointSpacing(n);
    const bool camera = !session.camera_frames().empty();
    int last_frame = -1, last_saved = 0;  // none at 0: the GUI's player keeps its own there
    std::vector<LinkContact> link_contacts;
    for (int k = 0; k < n; ++k) {
      if (stop_) return;
      // Light, and just before a sample that captures a frame: a player resumed here draws that
      // frame's pictures afresh (a full checkpoint holds a few MB of them).
      if (k >= last_saved + spacing && (!camera || player.CapturesFrame(k))) {
        Saved saved{player.Save(true), last_frame};
        std::lock_guard<std::mutex> lock(mutex_);
        checkpoints_.emplace(k, std::move(saved));
        last_saved = k;
      }
      player.Step(k);
      if (player.last_frame() >= 0) last_frame = player.last_frame();
      found.t.push_back(session.t(k));
      for (std::size_t i = 0; i < num_sets; ++i) {
        const EstimateRecord& r = player.last(i);
        Set& s = found.sets[i];
        s.events.insert(s.events.end(), r.events.begin(), r.events.end());
        const bool truth = std::isfinite(r.position_error);
        s.position_error.push_back(static_cast<float>(truth ? r.position_error * 1000 : kNaN));
        s.orientation_error.push_back(
            static_cast<float>(truth ? r.orientation_error * 180 / M_PI : kNaN));
        s.sigma_position.push_back(static_cast<float>(r.sigma_position.maxCoeff() * 1000));
        s.sigma_orientation.push_back(
            static_cast<float>(r.sigma_orientation.maxCoeff() * 180 / M_PI));
        s.nees.push_back(static_cast<float>(truth ? r.nees : kNaN));
        s.penetration.push_back(static_cast<float>(r.penetration * 1000));
        s.constraints.push_back(static_cast<float>(r.constraints));
        s.gated.push_back(static_cast<float>(r.gated));
        s.visual_mahalanobis.push_back(static_cast<float>(r.visual_mahalanobis));
        s.unexplained_torque.push_back(static_cast<float>(r.unexplained_torque));
        const Filter& filter = player.tracker(i).filter();
        double mahalanobis = 0.0, force = 0.0;
        int constraints = 0;
        for (const FilterTrace::Contact& c : filter.trace().contacts) {
          const bool constraint =
              !c.gated && (c.kind == ContactKind::kKinematic || c.kind == ContactKind::kTorque);
          if (constraint) mahalanobis += c.mahalanobis, ++constraints;
          if (c.kind == ContactKind::kTorque) force += c.force_P.norm();
        }
        s.contact_mahalanobis.push_back(
            static_cast<float>(constraints > 0 ? mahalanobis / constraints : kNaN));
        s.contact_force.push_back(static_cast<float>(force));
        for (const FilterTrace::Visual& v : filter.trace().visual)
          s.visual.push_back({static_cast<float>(session.t(k)), v.id,
                              static_cast<float>((v.measured - v.predicted).norm()),
                              static_cast<float>(v.mahalanobis), v.gated});
        LinkContacts(filter.trace(), player.models().hand.links.size(), link_contacts);
        const auto per_link = [&](std::vector<std::vector<float>>& series, auto value) {
          series.resize(link_contacts.size());
          for (std::size_t l = 0; l < link_contacts.size(); ++l)
            series[l].push_back(static_cast<float>(value(link_contacts[l])));
        };
        per_link(s.link_distance, [](const LinkContact& l) { return l.distance * 1000; });
        per_link(s.link_force, [](const LinkContact& l) { return l.force; });
        per_link(s.link_mahalanobis, [](const LinkContact& l) { return l.mahalanobis; });
        s.link_status.resize(link_contacts.size());
        for (std::size_t l = 0; l < link_contacts.size(); ++l)
          s.link_status[l].push_back(static_cast<std::uint8_t>(link_contacts[l].status));
        const auto cov = filter.covariance();
        s.bias.resize(static_cast<std::size_t>(r.biases.size()));
        s.sigma_bias.resize(s.bias.size());
        for (long j = 0; j < r.biases.size(); ++j) {
          const auto at = static_cast<std::size_t>(j);
          s.bias[at].push_back(static_cast<float>(r.biases[j] * 180 / M_PI));
          s.sigma_bias[at].push_back(
              static_cast<float>(std::sqrt(std::max(0.0, cov(6 + j, 6 + j))) * 180 / M_PI));
        }
        const Mat6 P = player.tracker(i).claimed_pose_covariance();
        const Mat3 R = r.T_PO.linear();
        const Vec3 var_p = (R.transpose() * P.topLeftCorner<3, 3>() * R).diagonal();
        const Vec3 var_o = (R.transpose() * P.bottomRightCorner<3, 3>() * R).diagonal();
        for (int a = 0; a < 3; ++a) {
          const auto at = static_cast<std::size_t>(a);
          s.position_error_axis[at].push_back(
              static_cast<float>(truth ? r.position_error_O[a] * 1000 : kNaN));
          s.orientation_error_axis[at].push_back(
              static_cast<float>(truth ? r.orientation_error_O[a] * 180 / M_PI : kNaN));
          s.sigma_position_axis[at].push_back(
              static_cast<float>(std::sqrt(std::max(0.0, var_p[a])) * 1000));
          s.sigma_orientation_axis[at].push_back(
              static_cast<float>(std::sqrt(std::max(0.0, var_o[a])) * 180 / M_PI));
        }
      }
      if (k % kPublish == kPublish - 1 && k != n - 1) publish(k, false);
    }
    for (std::size_t i = 0; i < num_sets; ++i) player.CloseEvents(i, found.sets[i].events);
    publish(n - 1, true);
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    data_.progress.done = true;
    data_.progress.error = e.what();
    ++version_;
  }
}

void VisualHistory(const SessionOverview::Data& data, int id, SessionOverview::Data& out,
                   std::vector<int>& images, std::vector<int>& gated) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  out.t = data.t;
  out.progress = data.progress;
  out.sets.resize(data.sets.size());
  images.assign(data.sets.size(), 0);
  gated.assign(data.sets.size(), 0);
  for (std::size_t i = 0; i < data.sets.size(); ++i) {
    const std::vector<VisualRecord>& records = data.sets[i].visual;
    std::vector<float>& residual = out.sets[i].visual_residual;
    std::vector<float>& mahalanobis = out.sets[i].visual_history_mahalanobis;
    residual.assign(data.t.size(), kNaN);
    mahalanobis.assign(data.t.size(), kNaN);
    // Walk the samples and the records together: an image's records share its sample's time.
    std::size_t r = 0;
    float value = kNaN, distance = kNaN;
    for (std::size_t k = 0; k < data.t.size(); ++k) {
      const float t = static_cast<float>(data.t[k]);
      if (r < records.size() && records[r].t <= t) {
        value = distance = kNaN;  // a new image: the id is measured in it or not at all
        const float image_t = records[r].t;
        bool measured = false;
        for (; r < records.size() && records[r].t == image_t; ++r)
          if (records[r].id == id) {
            value = records[r].residual, distance = records[r].mahalanobis, measured = true;
            gated[i] += records[r].gated;
          }
        images[i] += measured;
      }
      residual[k] = value;
      mahalanobis[k] = distance;
    }
  }
}

}  // namespace inhand::app
