// A user's program: tracks the object of a recorded session with inhand's online Tracker, sample
// by sample as a robot would call it, and prints the pose at each camera frame.
//
//   track_session SESSION_DIR [SET] [--threaded]      SET: j, jt, jta, jtf, ja, jf, ... (jt)
//
// Output: one line per camera frame and a last one,
//   t px py pz qw qx qy qz sigma_position_mm
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "inhand/core/error.hpp"
#include "inhand/core/time.hpp"
#include "inhand/sessions/session.hpp"
#include "inhand/tracker/tracker.hpp"

namespace {

void Print(const char* what, double t, const inhand::Tracker& tracker) {
  const inhand::Transform T_PO = tracker.T_PO();
  const Eigen::Quaterniond q(T_PO.linear());
  const double sigma = std::sqrt(tracker.covariance().topLeftCorner<3, 3>().trace());
  std::printf("%s %.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.3f\n", what, t, T_PO.translation().x(),
              T_PO.translation().y(), T_PO.translation().z(), q.w(), q.x(), q.y(), q.z(),
              sigma * 1000);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SESSION_DIR [SET] [--threaded]\n", argv[0]);
    return 2;
  }
  std::string set = "jt";
  inhand::TrackerOptions options;
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--threaded") == 0)
      options.threaded = true;
    else
      set = argv[i];
  }
  try {
    // The session names its hand (URDF) and object; both are loaded from there.
    const inhand::Session session = inhand::Session::Load(argv[1]);
    const inhand::SessionModels models = inhand::LoadSessionModels(session);
    const inhand::Modalities modalities{set.find('t') != std::string::npos,
                                        set.find('a') != std::string::npos,
                                        set.find('f') != std::string::npos};
    inhand::Tracker tracker(models.hand, models.object, modalities, inhand::TrackerParams(),
                            options);
    const inhand::SessionInfo& info = session.info();
    tracker.Start(session.num_samples() > 0 ? session.t(0) : 0.0, info.initial_T_PO,
                  inhand::StartSigmas{
                      info.sigma_position, info.sigma_orientation, info.sigma_joint_bias, {}});

    // The robot's loop: a joint sample at a time (in the hand's joint order), an image when one
    // has been captured.
    Eigen::VectorXd q(models.hand.num_q()), tau(models.hand.num_q());
    const auto& frames = session.camera_frames();
    const bool vision = modalities.tags || modalities.features;
    std::size_t next = 0;
    for (int k = 0; k < session.num_samples(); ++k) {
      const double t = session.t(k);
      for (std::size_t j = 0; j < models.joint_columns.size(); ++j) {
        q[static_cast<long>(j)] = session.q(k)[models.joint_columns[j]];
        tau[static_cast<long>(j)] = session.tau(k)[models.joint_columns[j]];
      }
      tracker.AddJointSample(t, q, tau);
      for (; next < frames.size() && frames[next].t <= t + inhand::kTimeTolerance; ++next) {
        if (vision)
          tracker.AddImage(frames[next].t, session.LoadImage(static_cast<int>(next)),
                           frames[next].T_PC, *info.camera);
        Print("frame", t, tracker);
      }
    }
    tracker.WaitForImages();
    Print("last", tracker.t(), tracker);
    const inhand::TrackerStats stats = tracker.stats();
    std::fprintf(stderr, "%s: %ld joint samples, %ld images fused, %ld dropped\n",
                 modalities.Name().c_str(), stats.samples, stats.images_fused,
                 stats.images_dropped_late + stats.images_dropped_busy);
  } catch (const inhand::InputError& e) {
    std::fprintf(stderr, "track_session: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
