#pragma once
// The tracker tests' recording: one simulated session read once per test process, and how the
// tests build trackers over it and feed it to them.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "inhand/sessions/session.hpp"
#include "inhand/tracker/tracker.hpp"
#include "test_support.hpp"

namespace inhand::test {

// One simulated session (ketchup bottle with its tag, paper noise), read once for every test.
struct Recording {
  TempDir dir;
  Session session;
  SessionModels models;
  std::vector<Eigen::VectorXd> q, tau;  // in the hand's order
  std::vector<Image8> images;

  static Recording& Get() {
    static Recording r;
    return r;
  }

 private:
  Recording() : session(Load(dir)), models(LoadSessionModels(session, true)) {
    for (int k = 0; k < session.num_samples(); ++k) {
      Eigen::VectorXd qk(models.hand.num_q()), tk(models.hand.num_q());
      for (std::size_t j = 0; j < models.joint_columns.size(); ++j) {
        qk[static_cast<long>(j)] = session.q(k)[models.joint_columns[j]];
        tk[static_cast<long>(j)] = session.tau(k)[models.joint_columns[j]];
      }
      q.push_back(qk), tau.push_back(tk);
    }
    for (std::size_t f = 0; f < session.camera_frames().size(); ++f)
      images.push_back(session.LoadImage(static_cast<int>(f)));
  }
  static Session Load(const TempDir& dir) {
    const auto r =
        RunInhand("simulate ketchup-power-grasp --noise paper --seed 2 --out " + (dir / "s"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return Session::Load(dir / "s");
  }
};

inline Modalities Set(const std::string& name) {
  return {name.find('t') != std::string::npos, name.find('a') != std::string::npos,
          name.find('f') != std::string::npos};
}

inline std::unique_ptr<Tracker> Make(const Recording& r, const std::string& set,
                                     TrackerOptions options = {}, TrackerParams params = {}) {
  auto tracker =
      std::make_unique<Tracker>(r.models.hand, r.models.object, Set(set), params, options);
  const SessionInfo& info = r.session.info();
  tracker->Start(
      r.session.t(0), info.initial_T_PO,
      StartSigmas{info.sigma_position, info.sigma_orientation, info.sigma_joint_bias, {}});
  return tracker;
}

// Feeds samples [from, n) and every `stride`-th camera frame once the joint samples have reached
// its capture time plus `delay` (frames reached before `from` are not fed again); `each` sees the
// tracker after every sample.
template <typename Each>
void Feed(const Recording& r, Tracker& tracker, int n, double delay, Each&& each,
          std::size_t stride = 1, int from = 0) {
  const auto& frames = r.session.camera_frames();
  std::size_t next = 0;
  while (from > 0 && next < frames.size() && frames[next].t + delay <= r.session.t(from - 1) + 1e-9)
    next += stride;
  for (int k = from; k < n; ++k) {
    const double t = r.session.t(k);
    tracker.AddJointSample(t, r.q[static_cast<std::size_t>(k)], r.tau[static_cast<std::size_t>(k)]);
    while (next < frames.size() && frames[next].t + delay <= t + 1e-9) {
      tracker.AddImage(frames[next].t, r.images[next], frames[next].T_PC, *r.session.info().camera);
      next += stride;
    }
    each(k);
  }
}

}  // namespace inhand::test
