#pragma once
// The whole session's events (tracker/events.hpp), for the GUI's timeline and event list: a player
// of its own replays the session on a background thread, without pictures, and publishes what it
// has found so far. The GUI's own player only knows the session up to the time shown.
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "inhand/app/player.hpp"

namespace inhand::app {

class EventOverview {
 public:
  // The session must outlive the overview; the work starts at once.
  EventOverview(const Session& session, const TrackerParams& params, std::vector<ModalitySet> sets);
  ~EventOverview();  // stops the work
  EventOverview(const EventOverview&) = delete;
  EventOverview& operator=(const EventOverview&) = delete;

  struct Progress {
    double t = 0.0;      // [s] the samples are replayed up to here
    double share = 0.0;  // of the session's samples
    bool done = false;
    std::string error;  // the replay failed (its message); done
  };
  // When what has been found changed since `version` (0 at first), copies every set's events
  // (in the order of `sets`) into `events` and returns the new version; otherwise returns
  // `version` and leaves `events` alone. `progress` is always filled.
  long Read(long version, std::vector<std::vector<TrackerEvent>>& events, Progress& progress) const;
  // Blocks until the whole session is replayed.
  void Wait();

 private:
  void Run(const Session& session, const TrackerParams& params, std::vector<ModalitySet> sets);
  mutable std::mutex mutex_;
  std::vector<std::vector<TrackerEvent>> events_;
  Progress progress_;
  long version_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace inhand::app
