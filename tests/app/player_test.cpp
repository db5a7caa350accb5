#include <gtest/gtest.h>

#include "inhand/app/player.hpp"
#include "inhand/sessions/session.hpp"

#include "test_support.hpp"

namespace inhand {
namespace {

using app::SessionPlayer;

// The GUI seeks back by restoring a checkpoint: the run from there must be bit-identical to the
// uninterrupted one, for every modality set, across camera frames (tags and extracted features).
TEST(SessionPlayer, CheckpointResumesBitIdentically) {
  test::TempDir dir;
  ASSERT_EQ(test::RunInhand("simulate ketchup-power-grasp --noise paper --seed 4 --out " + (dir / "session")).exit_code, 0);
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
  for (std::size_t i = 0; i < player.sets().size(); ++i) first_P.push_back(player.tracker(i).covariance());

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
  for (std::size_t i = 0; i < player.sets().size(); ++i) EXPECT_EQ(first_P[i], player.tracker(i).covariance());
  // The stretch replayed must hold camera frames, or the test would not cover the visual step.
  EXPECT_GE(frames, 8);
}

// At a camera frame the tag set reports its innovation (it was never set for jta), and a
// sample's gated count is its contacts' and features' once (the visual gates were added twice).
TEST(SessionPlayer, VisualRecordsOfTagsAndFeatures) {
  test::TempDir dir;
  ASSERT_EQ(test::RunInhand("simulate ketchup-power-grasp --noise paper --seed 5 --out " + (dir / "session")).exit_code, 0);
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

}  // namespace
}  // namespace inhand
