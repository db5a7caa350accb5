#pragma once
// Plays a recorded session into one Tracker per modality set (README, "The per-frame loop"):
// each joint sample in the hand's joint order, then the camera frames captured by then, and
// records every set's estimate and its comparison with the ground truth. Deterministic.
#include <memory>
#include <string>
#include <vector>

#include "inhand/app/evaluation.hpp"
#include "inhand/app/modalities.hpp"
#include "inhand/sessions/session.hpp"
#include "inhand/tracker/tracker.hpp"

namespace inhand::app {

class SessionPlayer {
 public:
  // `sets` empty: every set the session supports (jta only when the object carries tags, jta and
  // jtf only with camera images). The session must outlive the player.
  SessionPlayer(const Session& session, const TrackerParams& params,
                std::vector<ModalitySet> sets = {});
  int num_samples() const { return session_.num_samples(); }
  // Feeds joint sample k to every tracker (k = 0 starts them), then the camera frames captured
  // by it.
  void Step(int k);
  // Feeds samples k, k+1, ... to every set, up to and including the first that captures a camera
  // frame, at most max_samples of them; returns how many. The sets run on `jobs` threads (each
  // set on one thread at a time, every set's computation as in Step: the estimates are the
  // same bit for bit for any jobs). Every set's record of every sample goes to `records`
  // (sample-major: records[(s - k) * sets + i]); afterwards the player stands at the last one.
  int StepBlock(int k, int max_samples, int jobs, std::vector<EstimateRecord>& records);
  // The camera frame the last Step processed (-1: none) and its image (empty when no set sees
  // images).
  int last_frame() const { return state_.last_frame; }
  const Image8& last_image() const { return state_.image; }
  // The last feature set's last visual step (virtual image, matches, residuals): for `match`
  // and the GUI. Empty when no set uses extracted features.
  const VisualStep& last_feature_step() const;

  struct StepState {
    std::vector<EstimateRecord> last;
    std::size_t next_frame = 0;
    int last_frame = -1;
    Image8 image;
  };
  // Restoring a checkpoint and stepping on gives bit-identical estimates to an uninterrupted
  // run, so the GUI seeks back from the nearest checkpoint instead of from the start.
  struct Checkpoint {
    std::vector<TrackerSnapshot> trackers;
    StepState state;
  };
  // `light`: without the pictures (the camera image, each set's virtual view and matching
  // stages; tens of KB instead of a few MB). Stepping on from a light checkpoint gives the same
  // estimates, but the last frame's pictures are gone until the next frame is fused: save one just
  // before a sample that captures a frame (CapturesFrame), and Step it first.
  Checkpoint Save(bool light = false) const;
  void Restore(const Checkpoint& c);
  // Whether Step(k), after the samples before it, processes a camera frame.
  bool CapturesFrame(int k) const;

  const std::vector<ModalitySet>& sets() const { return sets_; }
  const Tracker& tracker(std::size_t i) const { return *trackers_[i]; }
  const EstimateRecord& last(std::size_t i) const { return state_.last[i]; }
  // Set i's bursts still open at the end of the recording (Tracker::CloseEvents), into `out`.
  void CloseEvents(std::size_t i, std::vector<TrackerEvent>& out);
  const Session& session() const { return session_; }
  const SessionModels& models() const { return models_; }
  const TrackerParams& params() const { return params_; }

  // What the session holds that the trackers will not use, found when the player is made: joint
  // samples no hand can produce (dropped; a session none of whose samples can be fused is
  // refused, InputError), frames captured before the first joint sample (dropped), ground truth
  // that does not cover every joint sample (no errors there).
  struct InputReport {
    struct Rejected {
      int sample = -1;
      int joint = -1;  // configuration index
      bool torque = false;
      double value = 0.0;
    };
    std::vector<Rejected> rejected_samples;
    int frames_before_first_sample = 0;
    double truth_from = 0.0, truth_to = 0.0;  // [s] ground truth's span (when there is truth)
    int samples_without_truth = 0;
    // One warning line each ("FILE:LINE: ..."), for stderr.
    std::vector<std::string> Warnings(const Session& session, const SessionModels& models,
                                      const TrackerParams& params) const;
    // "FILE:LINE: q:NAME = VALUE is ...": why a sample was rejected.
    static std::string Describe(const Session& session, const SessionModels& models,
                                const TrackerParams& params, const Rejected& r);
  };
  const InputReport& input_report() const { return report_; }

 private:
  const Session& session_;
  SessionModels models_;
  TrackerParams params_;
  std::vector<ModalitySet> sets_;
  std::vector<std::unique_ptr<Tracker>> trackers_;
  StepState state_;
  Eigen::VectorXd q_, tau_;  // joint sample k in the hand's order (for the report)
  std::vector<Eigen::VectorXd> set_q_, set_tau_;  // the same per set: sets may run in parallel
  void Gather(int k, Eigen::VectorXd& q, Eigen::VectorXd& tau) const;
  // Set i at sample k, then the frames [first_frame, end_frame) captured by it (their images in
  // images_); its record into r.
  void StepSet(std::size_t i, int k, std::size_t first_frame, std::size_t end_frame,
               EstimateRecord& r);
  // The frames captured by sample k from state_.next_frame on, loaded into images_; advances
  // state_.next_frame, last_frame and image.
  std::size_t LoadFramesOf(int k);
  std::vector<Image8> images_;  // the images of the frames the current step fuses
  bool TruthCovers(double t) const;
  // The NEES excursions beyond its bound, as events (EstimateRecord::events).
  static void WatchNees(EstimateRecord& r);
  VisualStep no_features_;
  InputReport report_;
};

}  // namespace inhand::app
