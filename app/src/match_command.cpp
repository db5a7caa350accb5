#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "inhand/app/commands.hpp"
#include "inhand/app/match_pictures.hpp"
#include "inhand/app/player.hpp"
#include "inhand/core/error.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/sessions/image_io.hpp"
#include "staged_output.hpp"

namespace fs = std::filesystem;

namespace inhand::app {

int RunMatch(const MatchCommand& cmd) {
  if (cmd.out.empty()) throw InputError("match: --out DIR is required");
  Session session = Session::Load(cmd.session);
  if (!session.info().camera) throw InputError(cmd.session + ": the session has no camera images");
  const int frames = static_cast<int>(session.camera_frames().size());
  if (cmd.frame < 0 || cmd.frame >= frames)
    throw InputError("--frame " + std::to_string(cmd.frame) +
                     " is out of range, the session has frames 0.." + std::to_string(frames - 1));
  SessionPlayer player(session, TrackerParams(), ParseModalities("jtf"));
  int k = 0;
  for (; k < session.num_samples(); ++k) {
    player.Step(k);
    if (player.last_frame() == cmd.frame) break;
  }
  // A copy, with the camera's corners for the pictures (the tracker does not compute them).
  VisualStep fs = player.last_feature_step();
  if (player.last_frame() != cmd.frame || fs.sequence == 0)
    throw InputError(cmd.session + ": frame " + std::to_string(cmd.frame) +
                     " comes after the last joint sample");
  fs.match.debug.real_corners = EdgeCorners(fs.match.debug.real_edges, player.params().features);
  const MatchResult& r = fs.match;
  const MatchDebug& d = r.debug;

  const MatchPictures pictures = DrawMatchPictures(player.last_image(), fs);

  StagedOutput out(cmd.out, {cmd.session}, "match");
  {
    const std::vector<std::pair<std::string, const Image8*>> images = {
        {"camera.png", &player.last_image()},
        {"virtual.png", &fs.virtual_view.colour},
        {"edges_camera.png", &pictures.edges_camera},
        {"edges_virtual.png", &pictures.edges_virtual},
        {"corners_camera.png", &pictures.corners_camera},
        {"corners_virtual.png", &pictures.corners_virtual},
        {"pieces.png", &pictures.pieces},
        {"hough_votes.png", &pictures.votes},
        {"matches.png", &pictures.matches},
        {"difference.png", &pictures.difference},
        {"stages.png", &pictures.stages}};
    for (const auto& [name, image] : images) WriteImage((out / name).string(), *image);

    jsonf::Json list = jsonf::Json::array();
    for (const FeatureMatch& m : r.matches) {
      jsonf::Json j = {{"corner", m.id},
                       {"virtual_px", {m.virtual_px.x(), m.virtual_px.y()}},
                       {"camera_px", {m.real_px.x(), m.real_px.y()}},
                       {"vote_fraction", m.vote_fraction},
                       {"inlier", m.inlier},
                       {"used", false}};
      list.push_back(j);
    }
    for (std::size_t u = 0; u < fs.used_match.size(); ++u) {
      jsonf::Json& j = list[static_cast<std::size_t>(fs.used_match[u])];
      j["used"] = true;
      j["residual_before_px"] = fs.residual_before[u];
      j["residual_after_px"] = fs.residual_after[u];
    }
    const jsonf::Json doc = {{"session", cmd.session},
                             {"frame", cmd.frame},
                             {"t", session.t(k)},
                             {"virtual_corners", d.virtual_corners.size()},
                             {"camera_corners", d.real_corners.size()},
                             {"pieces_rejected", d.piece_rejected.size()},
                             {"votes_rejected", d.vote_rejected.size()},
                             {"matches", r.matches.size()},
                             {"inliers", r.num_inliers()},
                             {"features_used", fs.used_match.size()},
                             {"search_radius_px", fs.search_radius},
                             {"relocalized_m", fs.relocalized},
                             {"list", list}};
    std::ofstream(out / "matches.json") << doc.dump(2) << "\n";
    out.Commit();
  }
  double before = 0, after = 0;
  for (std::size_t u = 0; u < fs.residual_before.size(); ++u)
    before += fs.residual_before[u], after += fs.residual_after[u];
  const double count = std::max<double>(1.0, static_cast<double>(fs.residual_before.size()));
  std::cout << "frame " << cmd.frame << ": " << d.virtual_corners.size() << " virtual corners, "
            << r.matches.size() << " Hough matches, " << r.num_inliers() << " RANSAC inliers, "
            << fs.used_match.size() << " used; mean residual " << before / count << " px before, "
            << after / count << " px after the update";
  if (fs.relocalized > 0.0)
    std::cout << "; the estimate had lost the object, found again " << fs.relocalized * 1000
              << " mm away (its position sigma widened by that)";
  std::cout << "; pictures in " << cmd.out << "\n";
  return 0;
}

}  // namespace inhand::app
