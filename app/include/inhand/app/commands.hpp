#pragma once
// The CLI's commands as plain functions (main.cpp only parses arguments with CLI11).
// Each returns the process exit code; bad input surfaces as InputError, which main turns into
// one line on stderr and exit code 2.
#include <optional>
#include <string>
#include <vector>

#include "inhand/sessions/simulator.hpp"

namespace inhand::app {

struct ModelCommand {
  std::string file;                   // a hand URDF, or an object description (.json, or a
                                      // single-link URDF without joints: a YCB object)
  std::vector<std::string> packages;  // NAME=DIR
  bool json = false;
  bool object = false;  // load FILE as an object even if it could be a hand
  std::string render;   // PNG preview of the hand (or object), "" for none
};
int RunModel(const ModelCommand& cmd);

struct CompareCommand {
  std::string a, b;
  int max_channel_delta = 12;       // a pixel is bad when a channel differs by more
  double max_bad_fraction = 0.003;  // the images match when at most this fraction is bad
  std::string diff;                 // heat map PNG, "" for none
};
// Exit 0 within tolerance, 1 outside, 2 on unreadable input.
int RunCompare(const CompareCommand& cmd);

struct SimulateCommand {
  std::string scenario;
  std::string out;
  unsigned seed = 1;
  std::string noise = "paper";
  bool list = false;
  bool overwrite = false;
  bool no_images = false;
  std::string effects, without;  // realism effects (sessions/realism.hpp), comma-separated
};
int RunSimulate(const SimulateCommand& cmd);
// The simulator's options for `cmd` (not `list`), checked: scenario and output given, the noise
// profile and realism effects known. Throws InputError.
SimulateOptions SimulateOptionsOf(const SimulateCommand& cmd);

struct ImportCommand {
  std::string recording;
  bool list = false;
  std::string out;
  bool overwrite = false;
  std::string hand, object;
  std::vector<std::string> packages;  // NAME=DIR
  std::string joints, effort_is = "none", image, camera_info, palm_frame, camera_frame, object_pose;
  bool no_images = false;
  std::string initial_pose;     // x,y,z,qw,qx,qy,qz
  std::string initial_sigma;    // POS_M,ORIENT_RAD,BIAS_RAD
  std::string joint_stiffness;  // K, or NAME=K,...[,*=K] [N m/rad]
  std::optional<double> start, end, time_origin;
};
int RunImport(const ImportCommand& cmd);

struct ReplayCommand {
  std::string session;
  std::string out;
  std::string modalities;  // "" = every set the session supports
  std::string params;      // TrackerParams JSON, "" = defaults
  bool no_video = false;
  bool frames = false;       // also write each annotated frame as PNG
  bool no_timeline = false;  // pictures without the timeline strip
  // [MiB] the pictures' states held for the timeline strip, drawn after the one pass over the
  // session; a session that needs more replays its sets twice (first for the events) instead
  double picture_memory_mib = 1536.0;
  double video_fps = 30.0;  // sessions without a camera: the 3-D view's frame rate
  bool mcap = false;        // also write replay.mcap (Foxglove, Lichtblick)
  int jobs = 2;  // threads: the sets in parallel, the pictures beside them (1: sequential)
};
int RunReplay(const ReplayCommand& cmd);

struct TagsCommand {
  std::string image;
  std::string family = "tag36h11";
  double decimate = 2.0;
  int refine_edges = 1;
  bool json = false;
};
int RunTags(const TagsCommand& cmd);

struct MatchCommand {
  std::string session;
  int frame = 0;
  std::string out;
};
// Runs jtf up to camera frame K and writes every matching stage as PNG plus matches.json.
int RunMatch(const MatchCommand& cmd);

struct EvaluateCommand {
  std::string out;
  std::string scenarios;  // comma-separated, "" = all
  int seeds = 5;
  int first_seed = 1;
  std::string noise = "paper";
  int jobs = 2;                             // runs in parallel (processes)
  std::string modalities = "j,jt,jta,jtf";  // the sets each run replays (j plus any of t, a, f)
  bool plan = false;                        // write plan.txt (one command line per run) and stop
  bool merge = false;                       // only build the tables and plots from existing runs
  bool keep_sessions = false;
  std::string params;  // tracker parameters (JSON) for every replay
};
// Simulates and replays every scenario x seed, then writes table1.md, table1.json and one
// Fig.-7-style plot per scenario.
int RunEvaluate(const EvaluateCommand& cmd, const std::string& self_binary);

}  // namespace inhand::app
