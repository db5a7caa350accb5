// inhand: command-line entry. Parsing only (CLI11 is slow to compile: keep it in this file).
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "inhand/app/commands.hpp"
#include "inhand/app/gui.hpp"
#include "inhand/core/error.hpp"

namespace {

// What `import` and `gui RECORDING` share: the options that say how to read the recording.
std::vector<CLI::Option*> AddImportOptions(CLI::App* cmd, inhand::app::ImportCommand& im) {
  std::vector<CLI::Option*> options;
  options.push_back(
      cmd->add_option("--hand", im.hand, "the hand's URDF (joint names are matched to it)"));
  options.push_back(
      cmd->add_option("--object", im.object, "the object model (object JSON or single-link URDF)"));
  options.push_back(
      cmd->add_option("--package", im.packages, "package:// resolution NAME=DIR (repeatable)"));
  options.push_back(cmd->add_option("--joints", im.joints,
                                    "sensor_msgs/JointState topic (default: the only one)"));
  options.push_back(
      cmd->add_option("--effort-is", im.effort_is,
                      "external: JointState effort is the external joint torque; none: no torques")
          ->capture_default_str());
  options.push_back(cmd->add_option(
      "--image", im.image, "sensor_msgs/Image or CompressedImage topic (default: the only one)"));
  options.push_back(
      cmd->add_flag("--no-images", im.no_images, "import joints (and ground truth) only"));
  options.push_back(
      cmd->add_option("--camera-info", im.camera_info,
                      "sensor_msgs/CameraInfo topic (default: beside the image topic)"));
  options.push_back(
      cmd->add_option("--palm-frame", im.palm_frame,
                      "TF frame of the URDF's root link (default: the root link's name)"));
  options.push_back(cmd->add_option("--camera-frame", im.camera_frame,
                                    "TF frame of the camera (default: the images' frame_id)"));
  options.push_back(
      cmd->add_option("--object-pose", im.object_pose,
                      "ground truth: PoseStamped, TransformStamped or Odometry topic"));
  options.push_back(
      cmd->add_option("--initial-pose", im.initial_pose,
                      "x,y,z,qw,qx,qy,qz in the palm frame (default: the first ground truth)"));
  options.push_back(cmd->add_option("--initial-sigma", im.initial_sigma,
                                    "POS_M,ORIENT_RAD,BIAS_RAD (default 0.02,0.087,0.087)"));
  options.push_back(
      cmd->add_option("--joint-stiffness", im.joint_stiffness,
                      "elastic joints, N m/rad: K for every joint, or NAME=K,...[,*=K] (needs "
                      "--effort-is external)"));
  options.push_back(
      cmd->add_option("--start", im.start, "seconds after the first joint sample to start at"));
  options.push_back(
      cmd->add_option("--end", im.end, "seconds after the first joint sample to end at"));
  options.push_back(cmd->add_option(
      "--time-origin", im.time_origin,
      "stamp [s since the epoch] that becomes t = 0 (default: the first joint sample's)"));
  return options;
}

// A folder with a session.json is a session; anything else is taken for a ROS recording.
bool IsSession(const std::string& path) {
  return std::filesystem::is_regular_file(std::filesystem::path(path) / "session.json");
}

// `gui RECORDING`: the recording imported as `import` would (with the same options) into a
// temporary session, which goes when the GUI closes.
int RunGuiOnRecording(inhand::app::GuiCommand gui, inhand::app::ImportCommand import) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("inhand-gui-" + std::to_string(::getpid()));
  struct Remove {
    fs::path dir;
    ~Remove() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } remove{dir};
  import.recording = gui.session;
  import.out = dir.string();
  import.overwrite = true;
  if (const int code = inhand::app::RunImport(import); code != 0) return code;
  gui.session = dir.string();
  return inhand::app::RunGui(gui);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"inhand: in-hand object pose estimation and its visual debugger"};
  cli.require_subcommand(1);

  inhand::app::ModelCommand model;
  auto* model_cmd =
      cli.add_subcommand("model", "Load a hand URDF or an object description and summarise it");
  model_cmd->add_option("FILE", model.file, "hand URDF, object .json or single-link object URDF")
      ->required();
  model_cmd->add_option("--package", model.packages, "resolve package://NAME as DIR (NAME=DIR)");
  model_cmd->add_flag("--json", model.json, "print JSON");
  model_cmd->add_flag("--object", model.object,
                      "load FILE as an object (a single-link URDF without joints is one anyway)");
  model_cmd->add_option("--render", model.render, "write a PNG preview (three views)");

  inhand::app::CompareCommand compare;
  auto* compare_cmd =
      cli.add_subcommand("compare",
                         "Compare two images, or two folders of frames pairwise (image "
                         "regression); exit 0 match, 1 differ, 2 unreadable");
  compare_cmd->add_option("A", compare.a, "first image, or folder of frames (replay --frames)")
      ->required();
  compare_cmd->add_option("B", compare.b, "second image, or folder of frames")->required();
  compare_cmd
      ->add_option("--max-channel-delta", compare.max_channel_delta,
                   "per-channel tolerance (0..255)")
      ->capture_default_str();
  compare_cmd
      ->add_option("--max-bad-fraction", compare.max_bad_fraction,
                   "allowed fraction of pixels beyond it")
      ->capture_default_str();
  compare_cmd->add_option(
      "--diff", compare.diff,
      "write a difference heat map (PNG; for folders: a folder, one per differing frame)");

  inhand::app::SimulateCommand simulate;
  auto* simulate_cmd =
      cli.add_subcommand("simulate", "Simulate one of the paper's experiments into a session");
  simulate_cmd->add_option("SCENARIO", simulate.scenario, "scenario name (--list shows them)");
  simulate_cmd->add_option("--out", simulate.out, "session directory to write");
  simulate_cmd->add_option("--seed", simulate.seed, "random seed (noise, biases, initial error)")
      ->capture_default_str();
  simulate_cmd
      ->add_option("--noise", simulate.noise, "noise profile: none, paper, hard or realistic")
      ->capture_default_str();
  simulate_cmd->add_option("--effects", simulate.effects,
                           "realism effects to simulate, comma-separated (object, hand, torque, "
                           "camera, all or one such as camera.jpeg; "
                           "default: all for realistic, none otherwise)");
  simulate_cmd->add_option("--without", simulate.without,
                           "realism effects to leave out, comma-separated");
  simulate_cmd->add_flag("--list", simulate.list, "list the scenarios");
  simulate_cmd->add_flag("--overwrite", simulate.overwrite,
                         "replace an existing session directory");
  simulate_cmd->add_flag("--no-images", simulate.no_images, "joints and ground truth only (fast)");

  inhand::app::ImportCommand import;
  auto* import_cmd = cli.add_subcommand(
      "import", "Import a ROS recording (ROS 1 bag, ROS 2 MCAP or .db3) into a session");
  import_cmd
      ->add_option("RECORDING", import.recording,
                   "the .bag, .mcap or .db3 file (or a ROS 2 bag folder)")
      ->required();
  import_cmd->add_flag("--list", import.list,
                       "list the topics (type, count, rate) and the TF frames, and stop");
  import_cmd->add_option("--out", import.out, "session directory to write");
  import_cmd->add_flag("--overwrite", import.overwrite, "replace an existing session directory");
  AddImportOptions(import_cmd, import);

  inhand::app::ReplayCommand replay;
  auto* replay_cmd = cli.add_subcommand(
      "replay", "Run the estimators over a session: estimates, summary, annotated video");
  replay_cmd->add_option("SESSION", replay.session, "session directory")->required();
  replay_cmd->add_option("--out", replay.out, "output directory (replaced when complete)")
      ->required();
  replay_cmd->add_option(
      "--modalities", replay.modalities,
      "comma-separated sets: j (joints) followed by any of t (+ torques), a (+ AprilTags), f (+ "
      "extracted features), e.g. j,jt,jta,jtf (default with torques) or j,ja,jf (without)");
  replay_cmd->add_option("--params", replay.params,
                         "tracker parameters (JSON, as written to params.json)");
  replay_cmd->add_flag("--no-video", replay.no_video, "skip replay.mp4");
  replay_cmd->add_flag("--frames", replay.frames, "also write every annotated frame as PNG");
  replay_cmd->add_flag("--no-timeline", replay.no_timeline,
                       "pictures without the timeline strip of events under them");
  replay_cmd
      ->add_option("--picture-memory", replay.picture_memory_mib,
                   "MiB the pictures may hold until the session's events are known (the "
                   "timeline strip shows them ahead); a session that needs more is replayed "
                   "twice instead, first without pictures")
      ->capture_default_str();
  replay_cmd->add_flag(
      "--mcap", replay.mcap,
      "also write replay.mcap for Foxglove/Lichtblick (poses, errors, image + overlays, contacts)");
  replay_cmd
      ->add_option("--video-fps", replay.video_fps,
                   "sessions without a camera: frame rate of the 3-D view video")
      ->capture_default_str();
  replay.jobs = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 16u));
  replay_cmd
      ->add_option("--jobs", replay.jobs,
                   "threads: the modality sets in parallel and the pictures beside them; 1 runs "
                   "everything in order on one thread (the outputs are the same)")
      ->capture_default_str();

  inhand::app::TagsCommand tags;
  auto* tags_cmd = cli.add_subcommand("tags", "Detect AprilTags in an image (debugging)");
  tags_cmd->add_option("IMAGE", tags.image, "image file")->required();
  tags_cmd->add_option("--family", tags.family, "tag family")->capture_default_str();
  tags_cmd->add_option("--decimate", tags.decimate, "quad decimation (1 = full resolution)")
      ->capture_default_str();
  tags_cmd->add_option("--refine-edges", tags.refine_edges, "refine quad edges (0 or 1)")
      ->capture_default_str();
  tags_cmd->add_flag("--json", tags.json, "print JSON");

  inhand::app::MatchCommand match;
  auto* match_cmd = cli.add_subcommand(
      "match", "Debug the extracted-feature matching of one camera frame (PNG per stage + JSON)");
  match_cmd->add_option("SESSION", match.session, "session directory")->required();
  match_cmd->add_option("--frame", match.frame, "camera frame index")->required();
  match_cmd->add_option("--out", match.out, "output directory")->required();

  inhand::app::EvaluateCommand evaluate;
  auto* evaluate_cmd = cli.add_subcommand(
      "evaluate", "Simulate and replay every scenario x seed: Table I and Fig.-7 plots");
  evaluate_cmd->add_option("--out", evaluate.out, "output directory")->required();
  evaluate_cmd->add_option("--scenarios", evaluate.scenarios,
                           "comma-separated scenarios (default: all)");
  evaluate_cmd->add_option("--seeds", evaluate.seeds, "seeds per scenario")->capture_default_str();
  evaluate_cmd->add_option("--noise", evaluate.noise, "noise profile: paper, hard or realistic")
      ->capture_default_str();
  evaluate_cmd
      ->add_option("--first-seed", evaluate.first_seed,
                   "first seed (seeds first..first+N-1; tuned on 1-5, 101 and up unseen)")
      ->capture_default_str();
  evaluate_cmd->add_option("--jobs", evaluate.jobs, "runs in parallel")->capture_default_str();
  evaluate_cmd
      ->add_option("--modalities", evaluate.modalities, "comma-separated sets, as for replay")
      ->capture_default_str();
  evaluate_cmd->add_option("--params", evaluate.params,
                           "tracker parameters (JSON, as for replay) for every run");
  evaluate_cmd->add_flag("--plan", evaluate.plan, "write plan.txt (one command per run) and stop");
  evaluate_cmd->add_flag("--merge", evaluate.merge,
                         "only build tables and plots from existing runs");
  evaluate_cmd->add_flag("--keep-sessions", evaluate.keep_sessions, "keep the simulated images");

  inhand::app::GuiCommand gui;
  auto* gui_cmd = cli.add_subcommand(
      "gui",
      "Interactive session (Dear ImGui) when a display exists; --screenshot renders offscreen");
  gui_cmd
      ->add_option("SESSION", gui.session,
                   "session directory, or a ROS recording (.bag, .mcap, .db3 or a ROS 2 bag "
                   "folder) imported first with the import options (--hand, --object, ...)")
      ->required();
  gui_cmd->add_option("--params", gui.params,
                      "tracker parameters (JSON, as written to params.json)");
  gui_cmd->add_option(
      "--modalities", gui.modalities,
      "comma-separated sets, as for replay (default: every set the session supports)");
  gui_cmd->add_option("--frames", gui.frames, "quit after N frames");
  gui_cmd->add_option("--screenshot", gui.screenshot, "save the last frame as PNG");
  gui_cmd->add_option("--time", gui.time, "start at this session time [s]");
  gui_cmd->add_flag("--play", gui.play, "start playing");
  gui_cmd->add_option("--script", gui.script,
                      "run FILE's inputs and checks (seek, key, click, wait, screenshot, expect), "
                      "then quit; exit 1 when a check fails");
  inhand::app::ImportCommand gui_import;
  const std::vector<CLI::Option*> gui_import_options = AddImportOptions(gui_cmd, gui_import);

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (*model_cmd) return inhand::app::RunModel(model);
    if (*compare_cmd) return inhand::app::RunCompare(compare);
    if (*simulate_cmd) return inhand::app::RunSimulate(simulate);
    if (*import_cmd) return inhand::app::RunImport(import);
    if (*replay_cmd) return inhand::app::RunReplay(replay);
    if (*tags_cmd) return inhand::app::RunTags(tags);
    if (*match_cmd) return inhand::app::RunMatch(match);
    if (*gui_cmd) {
      if (IsSession(gui.session)) {
        for (const CLI::Option* o : gui_import_options)
          if (o->count() > 0)
            throw inhand::InputError(o->get_name() + " is an import option, but " + gui.session +
                                     " is a session (a folder with session.json), not a recording");
        return inhand::app::RunGui(gui);
      }
      return RunGuiOnRecording(gui, gui_import);
    }
    if (*evaluate_cmd) {
      char self[4096];
      const ssize_t n = ::readlink("/proc/self/exe", self, sizeof(self) - 1);
      return inhand::app::RunEvaluate(
          evaluate, n > 0 ? std::string(self, static_cast<std::size_t>(n)) : std::string(argv[0]));
    }
  } catch (const inhand::InputError& e) {
    std::cerr << "inhand: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "inhand: error: " << e.what() << "\n";
    return 2;
  }
  return 2;
}
