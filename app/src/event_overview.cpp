#include "inhand/app/event_overview.hpp"

#include <exception>
#include <utility>

namespace inhand::app {

EventOverview::EventOverview(const Session& session, const TrackerParams& params,
                             std::vector<ModalitySet> sets)
    : events_(sets.size()) {
  thread_ = std::thread(
      [this, &session, params, s = std::move(sets)]() mutable { Run(session, params, s); });
}

EventOverview::~EventOverview() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void EventOverview::Wait() {
  if (thread_.joinable()) thread_.join();
}

long EventOverview::Read(long version, std::vector<std::vector<TrackerEvent>>& events,
                         Progress& progress) const {
  std::lock_guard<std::mutex> lock(mutex_);
  progress = progress_;
  if (version == version_) return version;
  events = events_;
  return version_;
}

void EventOverview::Run(const Session& session, const TrackerParams& params,
                        std::vector<ModalitySet> sets) {
  try {
    SessionPlayer player(session, params, std::move(sets));
    const int n = player.num_samples();
    const std::size_t num_sets = player.sets().size();
    std::vector<std::vector<TrackerEvent>> found(num_sets);
    // Published every kPublish samples (and at the end): a copy under the lock each time.
    constexpr int kPublish = 250;
    const auto publish = [&](int k, bool done) {
      std::lock_guard<std::mutex> lock(mutex_);
      events_.resize(num_sets);
      for (std::size_t i = 0; i < num_sets; ++i) {
        events_[i].insert(events_[i].end(), found[i].begin(), found[i].end());
        found[i].clear();
      }
      progress_.t = session.t(k);
      progress_.share = n > 1 ? static_cast<double>(k) / (n - 1) : 1.0;
      progress_.done = done;
      ++version_;
    };
    for (int k = 0; k < n; ++k) {
      if (stop_) return;
      player.Step(k);
      for (std::size_t i = 0; i < num_sets; ++i) {
        const std::vector<TrackerEvent>& e = player.last(i).events;
        found[i].insert(found[i].end(), e.begin(), e.end());
      }
      if (k % kPublish == kPublish - 1 && k != n - 1) publish(k, false);
    }
    for (std::size_t i = 0; i < num_sets; ++i) player.CloseEvents(i, found[i]);
    publish(n - 1, true);
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    progress_.done = true;
    progress_.error = e.what();
    ++version_;
  }
}

}  // namespace inhand::app
