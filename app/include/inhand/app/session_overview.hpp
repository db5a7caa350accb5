#pragma once
// The whole session at a glance, for the GUI's timeline, plots and event list: a player of its own
// replays the session on a background thread, without pictures, and publishes what it has found so
// far — every set's events (tracker/events.hpp) and, per joint sample, the series the plots draw.
// The GUI's own player only knows the session up to the time shown.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "inhand/app/player.hpp"

namespace inhand::app {

// What one step's contacts made of one link, from the most telling of its pairs: a gated
// constraint over a fused one over a rejected torque candidate over a candidate (the enum's
// order: the larger value wins).
enum class ContactStatus { kNone, kCandidate, kRejected, kKinematic, kTorque, kGated };
const char* ContactStatusName(ContactStatus status);  // "none", "candidate", ...
struct LinkContact {
  ContactStatus status = ContactStatus::kNone;
  double distance = NAN;     // [m] signed, its nearest pair's (before the update)
  double force = NAN;        // [N] the torque-confirmed pairs' forces, summed (0: none)
  double mahalanobis = NAN;  // its constraints' largest (NaN: no constraint)
};
// One entry per link of the hand (`out` resized to num_links); links the trace does not name keep
// kNone. Allocates nothing once `out` has its size.
void LinkContacts(const FilterTrace& trace, std::size_t num_links, std::vector<LinkContact>& out);

// One visual measurement of an image a set fused (FilterTrace::Visual): when, which (a tag corner
// keeps its id, tag id × 4 + corner, from image to image; a feature match's id is only its index
// among that image's matches), its residual at the estimate before the update, its Mahalanobis
// distance and whether the gate refused it.
struct VisualRecord {
  float t = 0.0f;  // [s] the sample that fused the image
  int id = -1;
  float residual = 0.0f;  // [px] |measured − predicted|
  float mahalanobis = 0.0f;
  bool gated = false;
};

class SessionOverview {
 public:
  // The session must outlive the overview; the work starts at once.
  SessionOverview(const Session& session, const TrackerParams& params,
                  std::vector<ModalitySet> sets);
  ~SessionOverview();  // stops the work
  SessionOverview(const SessionOverview&) = delete;
  SessionOverview& operator=(const SessionOverview&) = delete;

  struct Progress {
    double t = 0.0;      // [s] the samples are replayed up to here
    double share = 0.0;  // of the session's samples
    bool done = false;
    std::string error;  // the replay failed (its message); done
  };
  // One set's events in the order found, and its series, one value per sample of Data::t (NaN
  // where there is no ground truth).
  struct Set {
    std::vector<TrackerEvent> events;
    std::vector<float> position_error, orientation_error;  // [mm], [deg]
    std::vector<float> sigma_position, sigma_orientation;  // [mm], [deg]: the largest axis's
    std::vector<float> nees;
    std::vector<float> penetration;  // [mm] the deepest link inside the estimate
    std::vector<float> constraints;  // contact blocks applied
    std::vector<float> gated;        // measurement blocks the gates rejected (contacts, vision)
    std::vector<float> visual_mahalanobis;   // mean over the last image's features
    std::vector<float> unexplained_torque;   // [N m] sets with torques
    std::vector<float> contact_mahalanobis;  // mean over the step's contact constraints
    std::vector<float> contact_force;        // [N] the torque contacts' forces, summed
    // Per axis of the object frame: the signed error (estimate − truth, EstimateRecord::
    // position_error_O, orientation_error_O; NaN without truth) and the σ along that axis
    // (√ of the diagonal of R̂ᵀ P R̂, P's position and orientation blocks, R̂ the estimate's
    // orientation): along and about a bottle's axis apart from across it.
    std::array<std::vector<float>, 3> position_error_axis, orientation_error_axis;  // [mm], [deg]
    std::array<std::vector<float>, 3> sigma_position_axis, sigma_orientation_axis;  // [mm], [deg]
    // Per joint (the hand's configuration order): its estimated bias and the bias's σ [deg].
    std::vector<std::vector<float>> bias, sigma_bias;
    // Per link (HandModel::links order): what the step's contact query and update made of it
    // (LinkContacts): signed distance [mm] and force [N] (NaN: not within the query's reach),
    // the Mahalanobis distance of its constraint (NaN: none) and its ContactStatus. Read copies
    // one link's (the rest stay empty): every link's would double what the overview holds.
    std::vector<std::vector<float>> link_distance, link_force, link_mahalanobis;
    std::vector<std::vector<std::uint8_t>> link_status;
    // Every visual measurement of every image the set fused, in time order.
    std::vector<VisualRecord> visual;
    // One measurement's history as per-sample series (filled by VisualHistory only): its residual
    // [px] and Mahalanobis distance in the last image fused at or before each sample, NaN where
    // that image did not measure it.
    std::vector<float> visual_residual, visual_history_mahalanobis;
  };
  struct Data {
    std::vector<double> t;  // [s] the samples replayed
    std::vector<Set> sets;  // in the order of the sets given
    Progress progress;
  };
  // Appends to `data` what was found since it was last read with the version this returned
  // (version < 0: `data` is cleared and gets everything); returns the new version. `progress`
  // is always brought up to date. Of the per-link series, link `link`'s only (-1: none; kAllLinks:
  // every link's); read another link with version < 0.
  static constexpr int kAllLinks = -2;
  long Read(long version, Data& data, int link = kAllLinks) const;
  // Blocks until the whole session is replayed.
  void Wait();

  // On its way the replay keeps a light checkpoint (SessionPlayer::Save) at least
  // CheckpointSpacing(samples) samples apart, each resuming at a sample that captures a camera
  // frame (in a session without a camera, at any), so that the GUI's player can seek anywhere it
  // has passed and step at most about that far, the frame it shows drawn afresh. The latest one
  // resuming at a sample in (after, at_most]: false when none. `resume` is the sample it resumes
  // at (Step it first), `last_frame` the last camera frame processed before it (-1: none).
  bool CheckpointIn(int after, int at_most, int& resume, SessionPlayer::Checkpoint& checkpoint,
                    int& last_frame) const;
  static int CheckpointSpacing(int samples) { return std::max(50, samples / 2000); }
  // The GUI's own full checkpoints, where the overview has not been yet.
  static int CheckpointEvery(int samples) { return std::max(125, samples / 50); }
  // The last sample the overview's checkpoints cover: its latest checkpoint's, or every sample
  // once the replay is done (-1: none yet).
  int CheckpointsReach() const;

 private:
  void Run(const Session& session, const TrackerParams& params, std::vector<ModalitySet> sets);
  mutable std::mutex mutex_;
  Data data_;
  std::size_t samples_ = 0;  // the session's samples, once the replay knows them
  struct Saved {
    SessionPlayer::Checkpoint checkpoint;
    int last_frame = -1;
  };
  std::map<int, Saved> checkpoints_;  // by the sample they resume at
  long version_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The history of visual measurement `id` in every set of `data` (VisualRecord, Set::
// visual_residual): `out` gets data's times and progress and, per set, the two series; `gated`
// and `images` count, per set, the images that gated it and those that measured it.
void VisualHistory(const SessionOverview::Data& data, int id, SessionOverview::Data& out,
                   std::vector<int>& images, std::vector<int>& gated);

}  // namespace inhand::app
