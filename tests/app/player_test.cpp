#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "inhand/app/frame_composer.hpp"
#include "inhand/app/player.hpp"
#include "inhand/app/session_overview.hpp"
#include "inhand/core/error.hpp"
#include "inhand/sessions/session.hpp"

#include "test_support.hpp"

namespace inhand {
namespace {

using app::SessionPlayer;

// The ketchup power grasp simulated with `options` into dir/session.
bool SimulateKetchup(const test::TempDir& dir, const std::string& options) {
  const test::CommandResult r =
      test::RunInhand("simulate ketchup-power-grasp " + options + " --out " + (dir / "session"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return r.exit_code == 0;
}

// The GUI seeks back by restoring a checkpoint: the run from there must be bit-identical to the
// uninterrupted one, for every modality set, across camera frames (tags and extracted features).
TEST(SessionPlayer, CheckpointResumesBitIdentically) {
  test::TempDir dir;
  ASSERT_TRUE(SimulateKetchup(dir, "--noise paper --seed 4"));
  Session session = Session::Load(dir / "session");
  SessionPlayer player(session, TrackerParams());
  ASSERT_EQ(player.sets().size(), 4u);
  const int mid = 400, end = 900;  // 500 Hz joints, 10 Hz camera: ten frames in between
  for (int k = 0; k < mid; ++k) player.Step(k);
  const SessionPlayer::Checkpoint checkpoint = player.Save();
  std::vector<std::vector<Transform>> first(player.sets().size());
  std::vector<Eigen::MatrixXd> first_P;
  for (int k = mid; k < end; ++k) {
    player.Step(k);
    for (std::size_t i = 0; i < player.sets().size(); ++i) first[i].push_back(player.last(i).T_PO);
  }
  for (std::size_t i = 0; i < player.sets().size(); ++i)
    first_P.push_back(player.tracker(i).covariance());

  player.Restore(checkpoint);
  int frames = 0;
  for (int k = mid; k < end; ++k) {
    player.Step(k);
    frames += player.last_frame() >= 0;
    for (std::size_t i = 0; i < player.sets().size(); ++i) {
      const Transform& a = first[i][static_cast<std::size_t>(k - mid)];
      const Transform& b = player.last(i).T_PO;
      ASSERT_EQ(a.matrix(), b.matrix()) << player.sets()[i].name << " at sample " << k;
    }
  }
  for (std::size_t i = 0; i < player.sets().size(); ++i)
    EXPECT_EQ(first_P[i], player.tracker(i).covariance());
  // The stretch replayed must hold camera frames, or the test would not cover the visual step.
  EXPECT_GE(frames, 8);
}

// The GUI's timeline and plots read the whole session from an overview replayed on a thread of
// its own: its events are replay's events.csv, event for event (time, kind, subject, value) and set
// for set, its series estimates.csv's; a second read with the version it returned adds nothing.
TEST(SessionOverview, FindsTheEventsAndSeriesReplayWrites) {
  test::TempDir dir;
  ASSERT_TRUE(SimulateKetchup(dir, "--noise paper --seed 4"));
  ASSERT_EQ(test::RunInhand("replay " + (dir / "session") +
                            " --no-video --modalities jt,jtf --out " + (dir / "replay"))
                .exit_code,
            0);
  Session session = Session::Load(dir / "session");
  const std::vector<app::ModalitySet> sets = app::ParseModalities("jt,jtf");
  app::SessionOverview overview(session, TrackerParams(), sets);
  overview.Wait();
  app::SessionOverview::Data data;
  const long version = overview.Read(-1, data);
  const app::SessionOverview::Progress& progress = data.progress;
  EXPECT_GT(version, 0);
  EXPECT_TRUE(progress.done);
  EXPECT_EQ(progress.error, "");
  EXPECT_DOUBLE_EQ(progress.share, 1.0);
  EXPECT_DOUBLE_EQ(progress.t, session.t(session.num_samples() - 1));
  ASSERT_EQ(data.sets.size(), 2u);
  ASSERT_EQ(data.t.size(), static_cast<std::size_t>(session.num_samples()));
  EXPECT_EQ(overview.Read(version, data), version);
  EXPECT_EQ(data.t.size(), static_cast<std::size_t>(session.num_samples()));  // nothing added
  // The copy holds the session's samples without the slack of growing by doubling (a 10-minute
  // session's series are hundreds of MB).
  EXPECT_EQ(data.t.capacity(), data.t.size());
  for (const app::SessionOverview::Set& s : data.sets) {
    EXPECT_EQ(s.position_error.capacity(), data.t.size());
    EXPECT_EQ(s.sigma_position_axis[2].capacity(), data.t.size());
    ASSERT_FALSE(s.bias.empty());
    EXPECT_EQ(s.bias.back().capacity(), data.t.size());
    ASSERT_FALSE(s.link_status.empty());
    EXPECT_EQ(s.link_status.back().capacity(), data.t.size());
  }
  // estimates.csv's position error and largest position sigma, per set, sample for sample.
  {
    std::ifstream in(dir / "replay/estimates.csv");
    std::string line;
    std::getline(in, line);
    std::map<std::string, std::size_t> row;
    double worst = 0.0, worst_trace = 0.0;
    std::array<double, 2> forces{};
    while (std::getline(in, line)) {
      std::vector<std::string> f;
      std::stringstream ss(line);
      for (std::string v; std::getline(ss, v, ',');) f.push_back(v);
      const std::size_t i = f.at(1) == "jt" ? 0 : 1;
      const std::size_t k = row[f[1]]++;
      ASSERT_LT(k, data.t.size());
      EXPECT_EQ(std::stod(f[0]), data.t[k]);
      worst = std::max(worst, std::abs(std::stod(f.at(15)) - data.sets[i].position_error[k]));
      const double sigma = std::max({std::stod(f[9]), std::stod(f[10]), std::stod(f[11])}) * 1000;
      worst = std::max(worst, std::abs(sigma - data.sets[i].sigma_position[k]));
      // Per axis of the object frame: the errors make the norm; the σ along the object's axes
      // and estimates.csv's along the palm's have the same sum of squares (P's trace).
      const app::SessionOverview::Set& o = data.sets[i];
      double e2 = 0.0, p2 = 0.0, r2 = 0.0, p2_palm = 0.0, r2_palm = 0.0;
      for (std::size_t a = 0; a < 3; ++a) {
        e2 += std::pow(o.position_error_axis[a][k], 2);
        p2 += std::pow(o.sigma_position_axis[a][k], 2);
        r2 += std::pow(o.sigma_orientation_axis[a][k], 2);
        p2_palm += std::pow(std::stod(f[9 + a]) * 1000, 2);
        r2_palm += std::pow(std::stod(f[12 + a]) * 180 / M_PI, 2);
      }
      worst = std::max(worst, std::abs(std::sqrt(e2) - o.position_error[k]));
      // Each joint's bias as estimates.csv gives it (after the 22 fixed columns), its σ within
      // the session's initial one.
      ASSERT_EQ(o.bias.size(), f.size() - 22);
      for (std::size_t j = 0; j < o.bias.size(); ++j) {
        worst = std::max(worst, std::abs(std::stod(f[22 + j]) * 180 / M_PI - o.bias[j][k]));
        EXPECT_GT(o.sigma_bias[j][k], 0.0f);
        EXPECT_LE(o.sigma_bias[j][k], session.info().sigma_joint_bias * 180 / M_PI * (1 + 1e-6));
      }
      // A Mahalanobis distance of the contacts exactly where constraints were applied.
      EXPECT_EQ(std::isfinite(o.contact_mahalanobis[k]), o.constraints[k] > 0) << k;
      forces[i] += o.contact_force[k];
      worst_trace = std::max(
          {worst_trace, std::abs(p2 - p2_palm) / p2_palm, std::abs(r2 - r2_palm) / r2_palm});
    }
    EXPECT_LT(worst, 1e-3);        // float
    EXPECT_LT(worst_trace, 1e-5);  // float, and estimates.csv's printed digits
  }
  // Per link (the inspector's history): a link with a fused constraint exactly at the samples
  // where constraints were applied (at most one link per block), the links' torque-contact forces
  // summing to the set's, a Mahalanobis distance exactly where a link has a constraint.
  for (const app::SessionOverview::Set& o : data.sets) {
    ASSERT_GT(o.link_status.size(), 5u);
    ASSERT_EQ(o.link_distance.size(), o.link_status.size());
    ASSERT_EQ(o.link_force.size(), o.link_status.size());
    ASSERT_EQ(o.link_mahalanobis.size(), o.link_status.size());
    int touching = 0;
    for (std::size_t k = 0; k < data.t.size(); ++k) {
      int fused = 0;
      double force = 0.0;
      for (std::size_t l = 0; l < o.link_status.size(); ++l) {
        const auto status = static_cast<app::ContactStatus>(o.link_status[l][k]);
        const bool constraint = status == app::ContactStatus::kKinematic ||
                                status == app::ContactStatus::kTorque ||
                                status == app::ContactStatus::kGated;
        fused += status == app::ContactStatus::kKinematic || status == app::ContactStatus::kTorque;
        EXPECT_EQ(std::isfinite(o.link_mahalanobis[l][k]), constraint) << k << " " << l;
        EXPECT_EQ(std::isfinite(o.link_distance[l][k]), status != app::ContactStatus::kNone);
        if (std::isfinite(o.link_force[l][k])) force += o.link_force[l][k];
      }
      EXPECT_EQ(fused > 0, o.constraints[k] > 0) << k;
      EXPECT_LE(fused, o.constraints[k]) << k;
      EXPECT_NEAR(force, o.contact_force[k], 1e-3 * (1 + force)) << k;
      touching += fused > 0;
    }
    EXPECT_GT(touching, static_cast<int>(data.t.size()) / 3);
  }
  // A read of one link's series (what the GUI keeps) has that link's, the same, and no other's.
  {
    app::SessionOverview::Data one;
    overview.Read(-1, one, 3);
    for (std::size_t i = 0; i < sets.size(); ++i) {
      const app::SessionOverview::Set &all = data.sets[i], &o = one.sets[i];
      ASSERT_EQ(o.link_distance.size(), all.link_distance.size());
      for (std::size_t l = 0; l < o.link_distance.size(); ++l) {
        EXPECT_EQ(o.link_status[l], l == 3 ? all.link_status[l] : std::vector<std::uint8_t>());
        EXPECT_EQ(o.link_force[l].size(), l == 3 ? data.t.size() : 0u);
      }
      EXPECT_EQ(o.position_error, all.position_error);
    }
  }
  // summary.json's per-set means of the counts and the unexplained torque.
  {
    std::ifstream in(dir / "replay/summary.json");
    const nlohmann::json summary = nlohmann::json::parse(in).at("modalities");
    for (std::size_t i = 0; i < sets.size(); ++i) {
      const nlohmann::json& m = summary.at(sets[i].name);
      double constraints = 0.0, unexplained = 0.0;
      for (std::size_t k = 0; k < data.t.size(); ++k)
        constraints += data.sets[i].constraints[k],
            unexplained += data.sets[i].unexplained_torque[k];
      const double n = static_cast<double>(data.t.size());
      EXPECT_NEAR(constraints / n, m.at("constraints_per_step_mean").get<double>(), 1e-9)
          << sets[i].name;
      EXPECT_NEAR(unexplained / n, m.at("unexplained_torque_Nm_mean").get<double>(), 1e-5)
          << sets[i].name;
      EXPECT_GT(constraints, 0.0) << sets[i].name;
    }
  }
  std::vector<std::vector<TrackerEvent>> events;
  for (const auto& s : data.sets) events.push_back(s.events);
  // events.csv: per set, in time order (the overview's are in the order found).
  std::map<std::string, std::vector<std::string>> csv;
  std::ifstream in(dir / "replay/events.csv");
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string t, set, kind, subject, value;
    std::getline(ss, t, ','), std::getline(ss, set, ','), std::getline(ss, kind, ',');
    std::getline(ss, subject, ','), std::getline(ss, value, ',');
    csv[set].push_back(t + " " + kind + " " + subject + " " + value);
  }
  const SessionModels models = LoadSessionModels(session, false);
  for (std::size_t i = 0; i < sets.size(); ++i) {
    std::stable_sort(events[i].begin(), events[i].end(),
                     [](const TrackerEvent& a, const TrackerEvent& b) { return a.t < b.t; });
    std::vector<std::string> found;
    for (const TrackerEvent& e : events[i])
      found.push_back(FormatDouble(e.t) + " " + EventKindName(e.kind) + " " +
                      EventSubject(e, models.hand) + " " + FormatDouble(e.value));
    EXPECT_GE(found.size(), 6u) << sets[i].name;
    EXPECT_EQ(found, csv[sets[i].name]) << sets[i].name;
  }
}

// The inspector's history of a tag corner: the overview's record of every visual measurement is
// what a player of its own, stepping every sample, finds in its filter's trace (two runs, one
// answer); a corner's history holds, at each sample, its residual and Mahalanobis distance in the
// last image fused, NaN before the first image and where that image did not see it.
TEST(SessionOverview, RecordsEveryVisualMeasurementForItsHistory) {
  test::TempDir dir;
  ASSERT_TRUE(SimulateKetchup(dir, "--noise paper --seed 5"));
  Session session = Session::Load(dir / "session");
  const std::vector<app::ModalitySet> sets = app::ParseModalities("jt,jta");
  app::SessionOverview overview(session, TrackerParams(), sets);
  SessionPlayer player(session, TrackerParams(), sets);
  std::vector<app::VisualRecord> expected;
  for (int k = 0; k < player.num_samples(); ++k) {
    player.Step(k);
    for (const FilterTrace::Visual& v : player.tracker(1).filter().trace().visual)
      expected.push_back({static_cast<float>(session.t(k)), v.id,
                          static_cast<float>((v.measured - v.predicted).norm()),
                          static_cast<float>(v.mahalanobis), v.gated});
  }
  overview.Wait();
  app::SessionOverview::Data data;
  overview.Read(-1, data);
  EXPECT_TRUE(data.sets[0].visual.empty());  // jt sees no image
  const std::vector<app::VisualRecord>& found = data.sets[1].visual;
  ASSERT_EQ(found.size(), expected.size());
  ASSERT_GT(found.size(), 40u);
  for (std::size_t r = 0; r < found.size(); ++r) {
    EXPECT_EQ(found[r].t, expected[r].t) << r;
    EXPECT_EQ(found[r].id, expected[r].id) << r;
    EXPECT_EQ(found[r].residual, expected[r].residual) << r;
    EXPECT_EQ(found[r].mahalanobis, expected[r].mahalanobis) << r;
    EXPECT_EQ(found[r].gated, expected[r].gated) << r;
  }
  // The corner seen first, its history sample by sample.
  const int id = found.front().id;
  app::SessionOverview::Data history;
  std::vector<int> images, gated;
  app::VisualHistory(data, id, history, images, gated);
  ASSERT_EQ(history.t, data.t);
  const std::vector<float>& residual = history.sets[1].visual_residual;
  ASSERT_EQ(residual.size(), data.t.size());
  std::map<float, const app::VisualRecord*> of_image;  // the corner's record per image time
  std::vector<float> image_times;
  for (const app::VisualRecord& r : found) {
    if (image_times.empty() || image_times.back() != r.t) image_times.push_back(r.t);
    if (r.id == id) of_image[r.t] = &r;
  }
  EXPECT_EQ(images[1], static_cast<int>(of_image.size()));
  EXPECT_EQ(images[0], 0);
  int measured = 0;
  for (std::size_t k = 0; k < data.t.size(); ++k) {
    const float t = static_cast<float>(data.t[k]);
    const auto last = std::upper_bound(image_times.begin(), image_times.end(), t);
    const auto it = last == image_times.begin() ? of_image.end() : of_image.find(*std::prev(last));
    if (it == of_image.end()) {
      EXPECT_TRUE(std::isnan(residual[k])) << k;
    } else {
      EXPECT_EQ(residual[k], it->second->residual) << k;
      EXPECT_EQ(history.sets[1].visual_history_mahalanobis[k], it->second->mahalanobis) << k;
      ++measured;
    }
  }
  EXPECT_GT(measured, static_cast<int>(data.t.size()) / 2);
}

// The overview keeps light checkpoints on its way, each just before a sample that captures a
// frame; a player restored from one (the GUI seeking to where it has not been) goes on
// bit-identically to one that stepped every sample, and its first step draws that frame's
// pictures afresh.
TEST(SessionOverview, ItsCheckpointsResumeBitIdentically) {
  test::TempDir dir;
  ASSERT_TRUE(SimulateKetchup(dir, "--noise paper --seed 4"));
  const Session session = Session::Load(dir / "session");
  const std::vector<app::ModalitySet> sets = app::ParseModalities("jt,jta,jtf");
  app::SessionOverview overview(session, TrackerParams(), sets);
  overview.Wait();
  const int n = session.num_samples(), spacing = app::SessionOverview::CheckpointSpacing(n);
  SessionPlayer::Checkpoint c;
  int resume = -1, last_frame = -2;
  EXPECT_FALSE(overview.CheckpointIn(-1, spacing - 1, resume, c, last_frame));
  ASSERT_TRUE(overview.CheckpointIn(-1, n / 2, resume, c, last_frame));
  EXPECT_LE(resume, n / 2);
  EXPECT_GT(resume, n / 2 - 2 * spacing);  // the camera captures every 50 samples
  EXPECT_FALSE(overview.CheckpointIn(resume, n / 2, resume, c, last_frame));  // none after it
  // Light: no pictures in it.
  EXPECT_TRUE(c.state.image.empty());
  for (const TrackerSnapshot& s : c.trackers) EXPECT_TRUE(s.visual.virtual_view.depth.empty());
  SessionPlayer stepped(session, TrackerParams(), sets), restored(session, TrackerParams(), sets);
  int frame = -1;
  for (int k = 0; k < resume; ++k) {
    stepped.Step(k);
    if (stepped.last_frame() >= 0) frame = stepped.last_frame();
  }
  EXPECT_EQ(last_frame, frame);
  EXPECT_TRUE(stepped.CapturesFrame(resume));
  restored.Restore(c);
  restored.Step(resume), stepped.Step(resume);
  EXPECT_EQ(restored.last_frame(), frame + 1);
  EXPECT_FALSE(restored.last_image().empty());
  EXPECT_EQ(restored.last_feature_step().virtual_view.depth,
            stepped.last_feature_step().virtual_view.depth);
  for (int k = resume + 1; k < n; ++k) {
    stepped.Step(k), restored.Step(k);
    for (std::size_t i = 0; i < sets.size(); ++i)
      ASSERT_TRUE(stepped.last(i).T_PO.matrix() == restored.last(i).T_PO.matrix() &&
                  stepped.last(i).biases == restored.last(i).biases)
          << sets[i].name << " sample " << k;
  }
}

// At a camera frame the tag set reports its innovation (it was never set for jta), and a
// sample's gated count is its contacts' and features' once (the visual gates were added twice).
TEST(SessionPlayer, VisualRecordsOfTagsAndFeatures) {
  test::TempDir dir;
  ASSERT_TRUE(SimulateKetchup(dir, "--noise paper --seed 5"));
  Session session = Session::Load(dir / "session");
  SessionPlayer player(session, TrackerParams(), app::ParseModalities("jta,jtf"));
  int frames = 0;
  for (int k = 0; k < 1200; ++k) {
    player.Step(k);
    for (std::size_t i = 0; i < 2; ++i) {
      const app::EstimateRecord& r = player.last(i);
      EXPECT_EQ(r.gated, player.tracker(i).trace().num_gated);
      if (player.last_frame() < 0) continue;
      EXPECT_GE(r.visual_ms, 0.0) << player.sets()[i].name;
      if (r.visual_used == 0) continue;
      EXPECT_GT(r.visual_mahalanobis, 0.0) << player.sets()[i].name << " at sample " << k;
      frames += i == 0;
    }
  }
  EXPECT_GE(frames, 5);  // frames where jta fused tag corners
}

// Modality sets are j plus any of t, a, f; one canonical name per combination, a distinct colour
// for each, and errors that say what was expected.
// The recording `sim` written again to `out` through the session writer, with `info` (its models'
// paths made absolute, so they stay where the simulator put them) and with or without torques.
void WriteCopy(const Session& sim, SessionInfo info, const std::string& out, bool torques) {
  info.hand_urdf = sim.Resolve(info.hand_urdf);
  info.object = sim.Resolve(info.object);
  for (auto& [name, path] : info.packages) path = sim.Resolve(path);
  SessionWriter w(out, info, sim.joint_names(), false, torques);
  for (int k = 0; k < sim.num_samples(); ++k)
    w.AddJointSample(sim.t(k), sim.q(k), torques ? Eigen::VectorXd(sim.tau(k)) : Eigen::VectorXd());
  for (std::size_t i = 0; i < sim.camera_frames().size(); ++i)
    w.AddCameraFrame(sim.camera_frames()[i].t, sim.LoadImage(static_cast<int>(i)),
                     sim.camera_frames()[i].T_PC);
  for (const GroundTruthSample& g : sim.groundtruth()) w.AddGroundTruth(g.t, g.T_PO);
  w.Commit();
}

// What the pictures say beside the numbers: a session whose start is 120° and 30 mm off and
// claims σ 2 mm / 1° (written again with that start). jta's tags see the object elsewhere on the
// first image (its HUD says so until the next image), find it there on the second, and for the
// second after that image its HUD line says how far away; jt never finds it. A set's `slipping`
// is its filter's (the grip loosened): the ketchup scenario loosens it at 4.5 s.
TEST(FrameComposer, TheHudSaysWhenTheObjectWasFoundAgainAndWhenTheGripLoosened) {
  test::TempDir dir;
  ASSERT_TRUE(SimulateKetchup(dir, "--noise paper --seed 2"));
  const Session sim = Session::Load(dir / "session");
  SessionInfo info = sim.info();
  info.initial_T_PO.linear() =
      ExpSO3(Vec3(0.0, 0.0, 120.0 * M_PI / 180)) * info.initial_T_PO.linear();
  info.initial_T_PO.translation() += 0.03 * sim.camera_frames()[0].T_PC.linear().col(0);
  info.sigma_position = 0.002;
  info.sigma_orientation = 1.0 * M_PI / 180;
  WriteCopy(sim, info, dir / "lost", true);
  const Session lost = Session::Load(dir / "lost");
  SessionPlayer player(lost, TrackerParams(), app::ParseModalities("jt,jta"));
  std::vector<int> found_samples(2, 0), slipping_samples(2, 0), elsewhere_samples(2, 0);
  double found_at = -1.0;
  for (int k = 0; k < lost.num_samples(); ++k) {
    player.Step(k);
    const double t = lost.t(k);
    const app::PictureState st = app::FrameComposer::Capture(player, -1, t);
    ASSERT_EQ(st.sets.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
      // The record the HUD and the MCAP export read.
      const app::EstimateRecord& r = st.sets[i].record;
      EXPECT_EQ(r.slipping, player.tracker(i).filter().trace().slipping);
      EXPECT_EQ(r.memory, player.tracker(i).visual_memory());
      elsewhere_samples[i] += r.memory.tag_disagreements > 0;
      EXPECT_FALSE(r.memory.features_lost());
      slipping_samples[i] += r.slipping;
      if (st.sets[i].found_again > 0.0) {
        ++found_samples[i];
        const TrackerStats stats = player.tracker(i).stats();
        EXPECT_EQ(stats.relocalizations, 1);
        EXPECT_EQ(st.sets[i].found_again, stats.last_relocalized);
        EXPECT_LE(t - stats.last_relocalization_t, 1.0);
        found_at = stats.last_relocalization_t;
      }
    }
  }
  EXPECT_EQ(found_samples[0], 0);
  EXPECT_GT(found_at, 0.0);
  EXPECT_GE(found_samples[1],
            400);  // the second after it at 500 Hz, give or take the last image's lag
  EXPECT_LE(found_samples[1], 501);
  EXPECT_GT(player.tracker(1).stats().last_relocalized, 0.02);
  EXPECT_GT(slipping_samples[0], 0);
  EXPECT_EQ(elsewhere_samples[0], 0);
  EXPECT_EQ(elsewhere_samples[1], 50);  // from the first image to the second, at 10 Hz
}

// The external view's depth cue: per finger, the gap from its link nearest to the last set's
// estimate. Against the object's distance field (exact distances to the mesh's triangles, not GJK
// on its convex pieces): the object's end lies on the surface, the link's end as far from it as
// the gap says; the grasping fingers touch.
TEST(FrameComposer, FingerGapsAgreeWithTheObjectsDistanceField) {
  test::TempDir dir;
  ASSERT_TRUE(SimulateKetchup(dir, "--noise none --seed 2"));
  const Session session = Session::Load(dir / "session");
  SessionPlayer player(session, TrackerParams(), app::ParseModalities("j"));
  const int k_end = session.num_samples() * 3 / 4;
  for (int k = 0; k <= k_end; ++k) player.Step(k);
  app::FrameComposer composer(player);
  const app::PictureState st = app::FrameComposer::Capture(player, -1, session.t(k_end));
  const std::vector<OverlayGap> gaps = composer.Gaps(st);
  const auto& field = player.models().object.field;
  ASSERT_TRUE(field && !field->empty());
  const Transform T_OP = st.sets.back().record.T_PO.inverse();
  int touching = 0;
  for (const OverlayGap& g : gaps) {
    EXPECT_LE(g.distance, 0.05);
    EXPECT_NEAR(field->Distance(T_OP * g.object_P), 0.0, 1e-3);
    EXPECT_NEAR(field->Distance(T_OP * g.link_P), g.distance, 1.5e-3) << g.distance;
    touching += g.distance <= 1e-3;
  }
  EXPECT_GE(gaps.size(), 4u);
  EXPECT_GE(touching, 3);
}

// Each set's HUD line says what the set claims beside what it gets wrong: the largest principal σ
// of its position and of its orientation (a covariance turned away from the axes, whose
// principal σ are 1, 3, 2 mm and 1, 5, 2 deg), the error only where there is ground truth.
TEST(FrameComposer, TheHudLineGivesTheLargestSigmaOfPositionAndOrientation) {
  app::PictureState::Set set;
  const Mat3 Q = ExpSO3(Vec3(0.3, -0.5, 0.8));
  const double deg = M_PI / 180;
  set.pose_covariance.topLeftCorner<3, 3>() =
      Q * Vec3(1e-3, 3e-3, 2e-3).cwiseAbs2().asDiagonal() * Q.transpose();
  set.pose_covariance.bottomRightCorner<3, 3>() =
      Q.transpose() * Vec3(1 * deg, 5 * deg, 2 * deg).cwiseAbs2().asDiagonal() * Q;
  set.pose_covariance.topRightCorner<3, 3>() = 1e-6 * Q;  // correlations do not enter
  set.pose_covariance.bottomLeftCorner<3, 3>() = 1e-6 * Q.transpose();
  EXPECT_NEAR(app::LargestSigma(set.pose_covariance.topLeftCorner<3, 3>()), 3e-3, 1e-12);
  set.record.constraints = 1;
  EXPECT_EQ(app::HudLine("j", set), "j: sigma 3.0 mm / 5.0 deg, 1 constraint");
  set.record.position_error = 0.0142;
  set.record.orientation_error = 6.1 * deg;
  set.record.constraints = 2;
  set.record.slipping = true;
  set.found_again = 0.0466;
  EXPECT_EQ(app::HudLine("jta", set),
            "jta: 14.2 mm / 6.1 deg, sigma 3.0 mm / 5.0 deg, 2 constraints, found again 46.6 mm "
            "away, grip loosened");
}

// A hand without torque sensors: the same recording with its tau: columns removed replays j
// bit-identically (torques never reach j), runs ja and jf by default, and refuses jt.
TEST(SessionPlayer, TorqueFreeSessionRunsJointsTagsAndFeatures) {
  test::TempDir dir;
  ASSERT_TRUE(SimulateKetchup(dir, "--noise paper --seed 6"));
  const Session sim = Session::Load(dir / "session");
  // Two copies through the same writer (a session.json round trip rounds the initial pose),
  // with and without the torque columns.
  for (const bool torques : {true, false})
    WriteCopy(sim, sim.info(), dir / (torques ? "with_tau" : "no_tau"), torques);
  const Session full = Session::Load(dir / "with_tau");
  const Session bare = Session::Load(dir / "no_tau");
  EXPECT_TRUE(full.has_torques());
  EXPECT_FALSE(bare.has_torques());
  {
    std::ifstream in(dir / "no_tau/joints.csv");
    std::string header;
    std::getline(in, header);
    EXPECT_EQ(header.find("tau:"), std::string::npos) << header;
  }
  SessionPlayer a(full, TrackerParams(), app::ParseModalities("j"));
  SessionPlayer b(bare, TrackerParams());
  ASSERT_EQ(b.sets().size(), 3u);
  EXPECT_EQ(b.sets()[1].name, "ja");
  EXPECT_EQ(b.sets()[2].name, "jf");
  const int n = 1500;
  int frames = 0;
  for (int k = 0; k < n; ++k) {
    a.Step(k);
    b.Step(k);
    ASSERT_EQ(a.last(0).T_PO.matrix(), b.last(0).T_PO.matrix()) << "sample " << k;
    frames += b.last_frame() >= 0 && b.last(1).visual_used > 0;
  }
  EXPECT_GE(frames, 5);  // ja fused tag corners
  try {
    SessionPlayer c(bare, TrackerParams(), app::ParseModalities("j,jt"));
    ADD_FAILURE() << "jt on a session without torques";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("needs joint torques"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("j,ja,jf"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace inhand
