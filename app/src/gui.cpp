#include "inhand/app/gui.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/osmesa.h>
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>
#include <utility>

#include <nlohmann/json.hpp>

#include "gui_gl.hpp"
#include "inhand/app/event_palette.hpp"
#include "inhand/app/frame_composer.hpp"
#include "inhand/app/match_pictures.hpp"
#include "inhand/app/player.hpp"
#include "inhand/app/session_overview.hpp"
#include "inhand/core/error.hpp"
#include "inhand/core/time.hpp"
#include "inhand/renderer/osmesa.hpp"
#include "inhand/renderer/timeline_strip.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand::app {

namespace {

enum class ActionKind {
  kTogglePlay,
  kStepSample,
  kStepFrame,
  kSeek,
  kRecompute,
  kSaveParams,
  kCompare  // value 0: B is the panel's parameters, 1: the parameter file's
};
struct Action {
  ActionKind kind;
  int value = 0;
};

// Everything the interface shows or edits; actions are applied between frames.
struct GuiState {
  bool playing = false;
  float speed = 1.0f;
  // Playback in a window follows the wall clock (a slow frame steps more samples); offscreen it
  // steps 1/30 s of the recording per frame, so that a script's run is the same every time.
  bool play_wall_clock = false;
  std::chrono::steady_clock::time_point play_last;  // the last frame that stepped playback
  double play_carry = 0.0;                          // [samples] not stepped yet
  int seek_sample = 0;
  float typed_time = 0.0f;
  bool editing_time = false;  // while typing, the field does not follow the replay
  FrameComposer::Orbit orbit;
  OverlayLayers layers;
  TrackerParams params;
  std::vector<ModalitySet> sets;  // empty: the session's default sets
  char params_path[512] = "params.json";
  std::deque<Action> actions;
  std::string status;
  bool pictures_dirty = true;
  // The whole session's events and series (SessionOverview), and how far they are known.
  SessionOverview::Data overview;
  long overview_version = -1;  // -1: copy whatever the overview has
  int overview_link = -1;      // the link whose series `overview` holds (the inspected one)
  // The history of the inspector's selected visual measurement (VisualHistory) in every set, for
  // the overview's version and the id it was made for; images that measured it and that gated it.
  SessionOverview::Data visual_history;
  long visual_history_version = -2;
  int visual_history_id = -1;
  std::vector<int> visual_history_images, visual_history_gated;
  // The A/B comparison: the session replayed with parameters B (Runner::compare), what B is, and
  // the quantity the Compare tab plots (CompareQuantity).
  SessionOverview::Data compare;
  long compare_version = -1;
  std::string compare_what;
  int compare_quantity = 0;
  bool open_compare = false;      // bring the Compare tab to the front
  bool timeline_contacts = true;  // contact events on the timeline and in [ ] jumps
  int error_axis = 0;  // the Errors tab: 0 norms and largest axes, 1-3 the object frame's x, y, z
  int bias_joint = 0;  // the Biases and counts tab's joint (configuration order)
  ImGuiTextFilter event_filter;
  double event_list_t = -1.0;  // [s] the time the event list last scrolled to
  // The time window the timeline and the plots share [s] (NaN: the whole session).
  double view_t0 = NAN, view_t1 = NAN;
  std::vector<char> hidden;  // per set: left out of the timeline and the plots (keys 1-9)
  bool help = false;         // the keys' help over the views (h)
  // The inspector: the set whose measurements it lists (-1: the last), and what is selected in
  // it, ringed in the views: a link's contacts or a visual measurement (FilterTrace::Visual::id).
  int inspect_set = -1, inspect_link = -1, inspect_visual = -1;
  bool open_inspector = false;  // a script's `select` brings the Inspector tab to the front
  // Where the composed picture was last drawn (window pixels) and its width in pixels.
  ImVec2 picture_min{0, 0}, picture_max{0, 0};
  int picture_width = 0;
  bool Hidden(std::size_t set) const { return set < hidden.size() && hidden[set]; }
  // The layout (splitters), kept in the user's configuration folder (GuiLayout).
  float panel_width = 330.0f;  // [px] the left panel
  // Of the views' width, the composed picture's (its aspect kept). By default the camera panel
  // (two thirds of the picture) is half the views' width and the picture leaves the timeline and
  // plots most of the height.
  float picture_share = 0.75f;
  bool layout_changed = false;
};

// The layout's bounds: the panel keeps its controls readable and leaves the views 300 px; the
// picture keeps at least a fifth of the views' width.
constexpr float kMinPanelWidth = 220.0f, kMinViewsWidth = 300.0f, kMinPictureShare = 0.2f;

// The layout persisted between sessions in $XDG_CONFIG_HOME/inhand/gui.json (or
// ~/.config/inhand/gui.json), never in a session: the panel's width and the picture's share.
// A file that cannot be read as one is reported and left alone; the defaults are used.
std::filesystem::path GuiLayoutPath() {
  const char* xdg = std::getenv("XDG_CONFIG_HOME");
  const char* home = std::getenv("HOME");
  if (xdg && *xdg == '/') return std::filesystem::path(xdg) / "inhand/gui.json";
  if (home && *home) return std::filesystem::path(home) / ".config/inhand/gui.json";
  return {};
}

void LoadGuiLayout(GuiState& state) {
  const std::filesystem::path path = GuiLayoutPath();
  if (path.empty() || !std::filesystem::exists(path)) return;
  try {
    std::ifstream in(path);
    const nlohmann::json j = nlohmann::json::parse(in);
    const float panel = j.at("panel_width").get<float>();
    const float share = j.at("picture_share").get<float>();
    if (!(panel >= kMinPanelWidth && panel <= 4000.0f) ||
        !(share >= kMinPictureShare && share <= 1.0f))
      throw std::runtime_error("panel_width in [220, 4000] and picture_share in [0.2, 1]");
    state.panel_width = panel;
    state.picture_share = share;
  } catch (const std::exception& e) {
    std::cerr << "inhand: " << path.string()
              << ": not a layout (expected {\"panel_width\": PX, \"picture_share\": S}; "
              << e.what() << "); the default layout is used\n";
  }
}

// Written beside and renamed into place, so that a crash never leaves half a file.
void SaveGuiLayout(const GuiState& state) {
  const std::filesystem::path path = GuiLayoutPath();
  if (!state.layout_changed || path.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path(), ec);
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << nlohmann::json{{"panel_width", state.panel_width},
                          {"picture_share", state.picture_share}}
               .dump(2)
        << "\n";
    if (!out) {
      std::cerr << "inhand: " << path.string() << ": cannot save the layout\n";
      return;
    }
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) std::cerr << "inhand: " << path.string() << ": cannot save the layout\n";
}

class Runner {
 public:
  Runner(Session& session, GuiState& state) : session_(session), state_(state) {
    Restart();
    RestartOverview();
  }
  // The whole session again, with the current parameters (after they changed).
  void RestartOverview() {
    overview_.reset();  // stops the old one first
    overview_ = std::make_unique<SessionOverview>(session_, state_.params, player_->sets());
    state_.overview_version = -1;
    state_.visual_history_version = -2;
  }
  void Restart() {
    player_ = std::make_unique<SessionPlayer>(session_, state_.params, state_.sets);
    composer_ = std::make_unique<FrameComposer>(*player_);
    composer_->layout = FrameComposer::Layout::kCameraLarge;
    ForgetVisual();
    next_ = 0;
    last_frame_ = -1;
    checkpoints_.clear();
    // The start too: a seek back before the first checkpoint restores it instead of making the
    // player and its renderer again (0.4-0.6 s).
    checkpoints_.emplace(0, RunnerCheckpoint{player_->Save(), -1});
    StepTo(0);
  }
  // Deterministic: a seek resumes from the nearest checkpoint at or before k (the run from there
  // is bit-identical to the first), so it never drifts: the overview's (light, each resuming at a
  // sample that captures a frame, so that its pictures are drawn afresh; SessionOverview::
  // CheckpointSpacing apart) wherever it has passed, going back or forward, and this player's own
  // (full, at the start and every CheckpointEvery() samples beyond the overview's reach).
  void StepTo(int k) {
    k = std::clamp(k, 0, session_.num_samples() - 1);
    // Those of our checkpoints the overview's cover since: its serve.
    const int reach = overview_ ? overview_->CheckpointsReach() : -1;
    for (auto it = checkpoints_.begin(); it != checkpoints_.end();)
      it = it->first > 0 && it->first <= reach ? checkpoints_.erase(it) : std::next(it);
    const bool back = k < next_ - 1;
    // The latest checkpoint resuming at or before k + 1 (after next_ unless going back).
    const int after = back ? -1 : next_;
    int resume = -1;
    auto it = checkpoints_.upper_bound(k + 1);
    if (it != checkpoints_.begin() && std::prev(it)->first > after) resume = std::prev(it)->first;
    SessionPlayer::Checkpoint from_overview;
    int overview_resume = -1, overview_frame = -1;
    if (overview_ && overview_->CheckpointIn(std::max(after, resume), k, overview_resume,
                                             from_overview, overview_frame)) {
      player_->Restore(from_overview);
      ForgetVisual();
      next_ = overview_resume;
      last_frame_ = overview_frame;
      state_.pictures_dirty = true;
    } else if (resume >= 0) {
      const RunnerCheckpoint& c = checkpoints_.at(resume);
      player_->Restore(c.player);
      ForgetVisual();
      next_ = resume;
      last_frame_ = c.last_frame;
      state_.pictures_dirty = true;
    } else if (back) {
      Restart();
    }
    while (next_ <= k) {
      player_->Step(next_);
      KeepVisual();
      if (player_->last_frame() >= 0)
        last_frame_ = player_->last_frame(), state_.pictures_dirty = true;
      if (!session_.info().camera)
        state_.pictures_dirty = true;  // the 3-D view follows every sample
      ++next_;
      // Only where the overview's do not reach yet: a checkpoint holds a few MB of images, and
      // the overview's serve going back as well as forward.
      if (next_ % CheckpointEvery() == 0 && !checkpoints_.count(next_) &&
          next_ > (overview_ ? overview_->CheckpointsReach() : -1))
        checkpoints_.emplace(next_, RunnerCheckpoint{player_->Save(), last_frame_});
    }
  }
  void StepFrame() {
    const int target = last_frame_ + 1;
    while (next_ < session_.num_samples() && last_frame_ < target) StepTo(next_);
  }
  // The A/B comparison: the whole session replayed again, in the background, with parameters B;
  // A is what the views show (the player's parameters). Null until started.
  void StartCompare(const TrackerParams& b) {
    compare_.reset();  // stops the old one first
    compare_ = std::make_unique<SessionOverview>(session_, b, player_->sets());
    state_.compare_version = -1;
  }
  SessionOverview* compare() { return compare_.get(); }
  // Where the last picture drew its 3-D view (FrameComposer::last_external_view).
  const FrameComposer::ExternalView& external_view() const {
    return composer_->last_external_view();
  }
  Image8 Picture() {
    composer_->orbit = state_.orbit;
    composer_->selection = {
        state_.inspect_set < 0 ? static_cast<int>(player_->sets().size()) - 1 : state_.inspect_set,
        state_.inspect_link, state_.inspect_visual};
    const double t = session_.t(std::max(0, next_ - 1));
    // Without a camera: the external 3-D view of the grasp (hand, estimates, contacts, forces).
    if (!session_.info().camera)
      return next_ > 0 ? composer_->ComposeExternal(t, 960, 720, state_.layers) : Image8();
    if (last_frame_ < 0) return Image8();
    return composer_->Compose(last_frame_, t, state_.layers);
  }
  int SampleAt(double t) const {
    int k = 0;
    while (k + 1 < session_.num_samples() && session_.t(k + 1) <= t) ++k;
    return k;
  }
  // Set i's measurements of the last image it fused, and that image's time (NaN: none since the
  // player was last restored or restarted).
  const std::vector<FilterTrace::Visual>& visual(std::size_t i) const { return visual_[i]; }
  double visual_t(std::size_t i) const { return visual_t_[i]; }
  int sample() const { return next_ - 1; }
  int frame() const { return last_frame_; }
  const SessionPlayer& player() const { return *player_; }
  Session& session() { return session_; }
  SessionOverview& overview() { return *overview_; }

 private:
  Session& session_;
  GuiState& state_;
  std::unique_ptr<SessionPlayer> player_;
  std::unique_ptr<FrameComposer> composer_;
  std::unique_ptr<SessionOverview> overview_;
  std::unique_ptr<SessionOverview> compare_;
  int next_ = 0;
  int last_frame_ = -1;
  // Keyed by the sample the run resumes at. A checkpoint holds the last camera and virtual
  // images (a few MB): one at the start, then every CheckpointEvery() samples where the overview
  // has none yet (at most ~50 per session).
  int CheckpointEvery() const { return SessionOverview::CheckpointEvery(session_.num_samples()); }
  struct RunnerCheckpoint {
    SessionPlayer::Checkpoint player;
    int last_frame;
  };
  std::map<int, RunnerCheckpoint> checkpoints_;
  std::vector<std::vector<FilterTrace::Visual>> visual_;
  std::vector<double> visual_t_;
  void ForgetVisual() {
    visual_.assign(player_->sets().size(), {});
    visual_t_.assign(player_->sets().size(), NAN);
  }
  void KeepVisual() {
    for (std::size_t i = 0; i < player_->sets().size(); ++i) {
      const FilterTrace& trace = player_->tracker(i).filter().trace();
      if (!trace.visual.empty()) visual_[i] = trace.visual, visual_t_[i] = session_.t(next_);
    }
  }
};

// Brings the GUI's copy of the overview up to date; of the per-link series, the inspected link's.
// Whether a set's visual measurement ids name the same thing from image to image: tag corners
// (tag id × 4 + corner) do; a feature match's id is its index among one image's matches.
bool StableVisualIds(const ModalitySet& set) { return set.tags && !set.features; }

void ReadOverview(Runner& runner, GuiState& state) {
  if (state.inspect_link != state.overview_link)
    state.overview_version = -1, state.overview_link = state.inspect_link;
  state.overview_version =
      runner.overview().Read(state.overview_version, state.overview, state.overview_link);
  if (runner.compare())
    state.compare_version = runner.compare()->Read(state.compare_version, state.compare, -1);
  if (state.inspect_visual >= 0 && (state.visual_history_version != state.overview_version ||
                                    state.visual_history_id != state.inspect_visual)) {
    VisualHistory(state.overview, state.inspect_visual, state.visual_history,
                  state.visual_history_images, state.visual_history_gated);
    // The sets whose ids change meaning from image to image have no history to plot.
    const std::vector<ModalitySet>& sets = runner.player().sets();
    for (std::size_t i = 0; i < sets.size() && i < state.visual_history.sets.size(); ++i)
      if (!StableVisualIds(sets[i])) {
        state.visual_history.sets[i].visual_residual.clear();
        state.visual_history.sets[i].visual_history_mahalanobis.clear();
      }
    state.visual_history_version = state.overview_version;
    state.visual_history_id = state.inspect_visual;
  }
}

// Per set with tag corners, the images that measured the selected one and gated it, from the
// history ReadOverview made: "jta 41 images (0 gated), ..." ("" when it has none).
std::string VisualHistoryCounts(const Runner& runner, const GuiState& state) {
  const std::vector<ModalitySet>& sets = runner.player().sets();
  std::string counts;
  if (state.inspect_visual < 0 || state.visual_history_id != state.inspect_visual) return counts;
  for (std::size_t i = 0; i < sets.size() && i < state.visual_history_images.size(); ++i)
    if (StableVisualIds(sets[i]))
      counts += (counts.empty() ? "" : ", ") + sets[i].name + " " +
                std::to_string(state.visual_history_images[i]) + " images (" +
                std::to_string(state.visual_history_gated[i]) + " gated)";
  return counts;
}

// The set the inspector lists: the one chosen, else the last (the richest: it is drawn last and
// its virtual view is the middle panel).
std::size_t InspectedSet(const Runner& runner, const GuiState& state) {
  const std::size_t n = runner.player().sets().size();
  return state.inspect_set >= 0 && static_cast<std::size_t>(state.inspect_set) < n
             ? static_cast<std::size_t>(state.inspect_set)
             : n - 1;
}

struct Textures {
  Texture picture, camera_edges, virtual_edges, difference, corners, pieces, votes, matches;
  Texture patch_camera, patch_virtual;  // the inspector's selected visual measurement, zoomed
  bool has_patch_camera = false, has_patch_virtual = false;  // for the selection shown now
};

// The (2 half + 1)² pixels of an image (RGB, RGBA or grey) around `centre`, each drawn zoom × zoom,
// grey outside the image, with a yellow cross hair on the centre pixel; RGB.
Image8 ZoomedPatch(const Image8& image, const Vec2& centre, int half, int zoom) {
  const int side = (2 * half + 1) * zoom;
  Image8 out(side, side, 3);
  const int cx = static_cast<int>(std::lround(centre.x())),
            cy = static_cast<int>(std::lround(centre.y()));
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const int sx = cx - half + x / zoom, sy = cy - half + y / zoom;
      std::uint8_t* o = out.pixel(x, y);
      const bool inside = sx >= 0 && sy >= 0 && sx < image.width && sy < image.height;
      for (int c = 0; c < 3; ++c)  // a grey image's one channel in all three
        o[c] = inside ? image.pixel(sx, sy)[image.channels >= 3 ? c : 0] : 90;
      const int dx = x - half * zoom - zoom / 2, dy = y - half * zoom - zoom / 2;
      if ((dx == 0 || dy == 0) && std::abs(dx) + std::abs(dy) >= zoom &&
          std::abs(dx) + std::abs(dy) <= 3 * zoom)
        o[0] = 255, o[1] = 225, o[2] = 0;
    }
  return out;
}

void UpdateTextures(const GuiGl& gl, RenderThread& render, Runner& runner, GuiState& state,
                    Textures& tex) {
  if (!state.pictures_dirty) return;
  state.pictures_dirty = false;
  Image8 picture;
  render.Run([&] { picture = runner.Picture(); });
  tex.picture.Upload(gl, picture);
  const MatchPictures m =
      DrawMatchPictures(runner.player().last_image(), runner.player().last_feature_step());
  tex.camera_edges.Upload(gl, m.edges_camera);
  tex.virtual_edges.Upload(gl, m.edges_virtual);
  tex.difference.Upload(gl, m.difference);
  tex.corners.Upload(gl, m.corners_virtual);
  tex.pieces.Upload(gl, m.pieces);
  tex.votes.Upload(gl, m.votes);
  tex.matches.Upload(gl, m.matches);
  // The inspector's selected visual measurement: where the camera saw it, and where the virtual
  // image (feature sets) put it before the update.
  Image8 camera_patch, virtual_patch;
  const std::size_t set = InspectedSet(runner, state);
  for (const FilterTrace::Visual& v : runner.visual(set)) {
    if (v.id != state.inspect_visual) continue;
    const Image8& image = runner.player().last_image();
    if (!image.empty()) camera_patch = ZoomedPatch(image, v.measured, 12, 6);
    const VisualStep& step = runner.player().tracker(set).last_visual();
    if (step.has_features && !step.virtual_view.colour.empty())
      virtual_patch = ZoomedPatch(step.virtual_view.colour, v.predicted, 12, 6);
  }
  tex.patch_camera.Upload(gl, camera_patch);
  tex.patch_virtual.Upload(gl, virtual_patch);
  tex.has_patch_camera = !camera_patch.empty();
  tex.has_patch_virtual = !virtual_patch.empty();
}

void ApplyActions(Runner& runner, GuiState& state) {
  while (!state.actions.empty()) {
    const Action a = state.actions.front();
    state.actions.pop_front();
    switch (a.kind) {
      case ActionKind::kTogglePlay:
        state.playing = !state.playing;
        state.play_last = std::chrono::steady_clock::now(), state.play_carry = 0.0;
        break;
      case ActionKind::kStepSample:
        runner.StepTo(runner.sample() + 1), state.pictures_dirty = true;
        break;
      case ActionKind::kStepFrame:
        runner.StepFrame();
        break;
      case ActionKind::kSeek:
        runner.StepTo(a.value), state.pictures_dirty = true;
        break;
      case ActionKind::kRecompute: {
        try {
          state.params.Validate("GUI parameters");
          const int at = runner.sample();
          runner.Restart();
          runner.RestartOverview();
          runner.StepTo(at);
          state.status = "recomputed with the new parameters";
        } catch (const InputError& e) {
          state.status = e.what();
        }
        break;
      }
      case ActionKind::kCompare: {
        try {
          TrackerParams b = state.params;
          std::string what = "the panel's parameters";
          if (a.value == 1) {
            std::ifstream in(state.params_path);
            if (!in) throw InputError(std::string(state.params_path) + ": cannot read");
            std::stringstream text;
            text << in.rdbuf();
            b = TrackerParamsFromJson(text.str(), state.params_path);
            what = state.params_path;
          }
          b.Validate("B parameters");
          runner.StartCompare(b);
          state.compare_what = what;
          state.open_compare = true;
          state.status = "comparing with " + what + " (the Compare tab)";
        } catch (const InputError& e) {
          state.status = e.what();
        }
        break;
      }
      case ActionKind::kSaveParams: {
        std::ofstream out(state.params_path);
        out << TrackerParamsToJson(state.params) << "\n";
        state.status =
            out ? std::string("saved ") + state.params_path + " (replay --params accepts it)"
                : "cannot write " + std::string(state.params_path);
        break;
      }
    }
  }
  if (state.playing) {
    // Real time at `speed`: the recording's time that passed on the wall clock since the last
    // frame (at most 0.25 s of it: a frame that long shows that playback cannot keep up), or 1/30 s
    // per frame offscreen.
    const Session& s = runner.session();
    const double rate =
        s.num_samples() > 1 ? (s.num_samples() - 1) / (s.t(s.num_samples() - 1) - s.t(0)) : 100.0;
    const auto now = std::chrono::steady_clock::now();
    const double dt =
        state.play_wall_clock
            ? std::min(0.25, std::chrono::duration<double>(now - state.play_last).count())
            : 1.0 / 30.0;
    state.play_last = now;
    state.play_carry += rate * state.speed * dt;
    const int step = std::max(1, static_cast<int>(state.play_carry));
    state.play_carry = std::max(0.0, state.play_carry - step);
    runner.StepTo(runner.sample() + step);  // marks the pictures dirty when a camera frame arrives
    if (runner.sample() >= s.num_samples() - 1) state.playing = false;
  }
  state.seek_sample = runner.sample();
}

// The splitter between the panel and the views: a 8-px strip over their border; dragged, it
// moves the border (the window's width bounds it).
void DrawPanelSplitter(GuiState& state, int width, int height) {
  state.panel_width =
      std::clamp(state.panel_width, kMinPanelWidth,
                 std::max(kMinPanelWidth, static_cast<float>(width) - kMinViewsWidth));
  ImGui::SetNextWindowPos(ImVec2(state.panel_width - 4.0f, 0));
  ImGui::SetNextWindowSize(ImVec2(8.0f, static_cast<float>(height)));
  ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(0, 0));
  ImGui::Begin("panel splitter", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoBackground |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoMove);
  ImGui::InvisibleButton("##split", ImVec2(8.0f, static_cast<float>(height)));
  if (ImGui::IsItemHovered() || ImGui::IsItemActive())
    ImGui::SetMouseCursor(ImGuiMouseCursor_ResizeEW);
  if (ImGui::IsItemActive() && ImGui::GetIO().MouseDelta.x != 0.0f) {
    state.panel_width =
        std::clamp(state.panel_width + ImGui::GetIO().MouseDelta.x, kMinPanelWidth,
                   std::max(kMinPanelWidth, static_cast<float>(width) - kMinViewsWidth));
    state.layout_changed = true;
  }
  ImGui::End();
  ImGui::PopStyleVar();
}

// The left panel: playback, overlay layers, filter parameters.
void DrawControlPanel(Runner& runner, GuiState& state, int height) {
  const Session& s = runner.session();
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(state.panel_width, static_cast<float>(height)));
  ImGui::Begin("inhand", nullptr,
               ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse);
  ImGui::PushItemWidth(state.panel_width * 0.5f);  // leaves room for the longest label
  ImGui::TextWrapped("%s", s.info().name.c_str());
  ImGui::Text("t = %.3f s  sample %d/%d  frame %d", s.t(std::max(0, runner.sample())),
              runner.sample(), s.num_samples() - 1, runner.frame());
  if (ImGui::Button(state.playing ? "Pause" : "Play"))
    state.actions.push_back({ActionKind::kTogglePlay});
  ImGui::SameLine();
  if (ImGui::Button("+1 sample")) state.actions.push_back({ActionKind::kStepSample});
  ImGui::SameLine();
  if (ImGui::Button("+1 frame")) state.actions.push_back({ActionKind::kStepFrame});
  ImGui::SliderFloat("speed", &state.speed, 0.1f, 4.0f, "%.1fx");
  int seek = state.seek_sample;
  if (ImGui::SliderInt("sample", &seek, 0, s.num_samples() - 1))
    state.actions.push_back({ActionKind::kSeek, seek});
  if (!state.editing_time) state.typed_time = static_cast<float>(s.t(std::max(0, runner.sample())));
  ImGui::InputFloat("time [s]", &state.typed_time, 0.1f, 1.0f, "%.3f");
  state.editing_time = ImGui::IsItemActive();
  ImGui::SameLine();
  if (ImGui::Button("Go"))
    state.actions.push_back({ActionKind::kSeek, runner.SampleAt(state.typed_time)});
  ImGui::Text("3-D view: drag it to orbit, wheel to zoom");
  ImGui::TextUnformatted("keys: h (space, arrows, [ ], 1-9)");
  ImGui::Separator();
  ImGui::Text("Overlay layers");
  bool changed = false;
  changed |= ImGui::Checkbox("silhouettes", &state.layers.silhouette);
  changed |= ImGui::Checkbox("outlines", &state.layers.outline);
  changed |= ImGui::Checkbox("contacts", &state.layers.contacts);
  changed |= ImGui::Checkbox("forces", &state.layers.forces);
  changed |= ImGui::Checkbox("friction cones", &state.layers.cones);
  changed |= ImGui::Checkbox("features", &state.layers.features);
  changed |= ImGui::Checkbox("axes", &state.layers.axes);
  changed |= ImGui::Checkbox("3-sigma ellipse", &state.layers.uncertainty);
  changed |= ImGui::Checkbox("HUD", &state.layers.hud);
  if (changed) state.pictures_dirty = true;
  ImGui::Separator();
  ImGui::Text("Filter parameters");
  float sigma_mm = static_cast<float>(state.params.filter.contact_sigma * 1000);
  if (ImGui::SliderFloat("contact sigma [mm]", &sigma_mm, 0.1f, 20.0f))
    state.params.filter.contact_sigma = sigma_mm / 1000.0;
  float force = static_cast<float>(state.params.filter.force_min);
  if (ImGui::SliderFloat("force min [N]", &force, 0.0f, 10.0f))
    state.params.filter.force_min = force;
  float cone = static_cast<float>(state.params.filter.friction_cone_deg);
  if (ImGui::SliderFloat("friction cone [deg]", &cone, 5.0f, 90.0f))
    state.params.filter.friction_cone_deg = cone;
  float pixel = static_cast<float>(state.params.filter.pixel_sigma);
  if (ImGui::SliderFloat("pixel sigma [px]", &pixel, 0.5f, 10.0f))
    state.params.filter.pixel_sigma = pixel;
  float camera_mm = static_cast<float>(state.params.filter.camera_position_sigma * 1000);
  if (ImGui::SliderFloat("camera sigma [mm]", &camera_mm, 0.0f, 10.0f))
    state.params.filter.camera_position_sigma = camera_mm / 1000.0;
  float camera_deg = static_cast<float>(state.params.filter.camera_orientation_sigma * 180 / M_PI);
  if (ImGui::SliderFloat("camera sigma [deg]", &camera_deg, 0.0f, 3.0f))
    state.params.filter.camera_orientation_sigma = camera_deg * M_PI / 180;
  ImGui::SliderInt("contact iterations", &state.params.filter.contact_iterations, 1, 5);
  ImGui::Checkbox("normal-only contacts", &state.params.filter.contact_normal_only);
  if (ImGui::Button("Recompute from the start")) state.actions.push_back({ActionKind::kRecompute});
  ImGui::InputText("file", state.params_path, sizeof(state.params_path));
  if (ImGui::Button("Save parameters")) state.actions.push_back({ActionKind::kSaveParams});
  // A/B: the views stay as they are (A); B is replayed in the background.
  if (ImGui::Button("Compare: these")) state.actions.push_back({ActionKind::kCompare, 0});
  ImGui::SameLine();
  if (ImGui::Button("Compare: the file")) state.actions.push_back({ActionKind::kCompare, 1});
  if (!state.status.empty()) ImGui::TextWrapped("%s", state.status.c_str());
  ImGui::PopItemWidth();
  ImGui::End();
}

// Each set's joint biases now, as a histogram per set (one bar per joint, ±6°).
void DrawBiases(const SessionPlayer& p, float avail) {
  const float w = (avail - 3 * ImGui::GetStyle().ItemSpacing.x) / 4;
  for (std::size_t i = 0; i < p.sets().size(); ++i) {
    const auto& b = p.last(i).biases;
    std::vector<float> deg(static_cast<std::size_t>(b.size()));
    for (long j = 0; j < b.size(); ++j)
      deg[static_cast<std::size_t>(j)] = static_cast<float>(b[j] * 180 / M_PI);
    const Rgb& c = p.sets()[i].colour;
    ImGui::PushStyleColor(ImGuiCol_PlotHistogram,
                          ImVec4(c.r / 255.f, c.g / 255.f, c.b / 255.f, 1.f));
    char id[48], text[96];
    std::snprintf(id, sizeof(id), "##bias%zu", i);
    std::snprintf(text, sizeof(text), "%s joint biases [deg], +-6", p.sets()[i].name.c_str());
    if (i % 4) ImGui::SameLine();
    ImGui::PlotHistogram(id, deg.data(), static_cast<int>(deg.size()), 0, text, -6.0f, 6.0f,
                         ImVec2(w, 44));
    ImGui::PopStyleColor();
  }
}

// The extracted-feature step of the last camera frame, stage by stage.
void DrawFeatureMatching(const SessionPlayer& p, const Textures& tex, float avail) {
  const float w = (avail - 16) / 3;
  // A row of three titled pictures.
  const auto row = [&](const std::array<const char*, 3>& titles,
                       const std::array<const Texture*, 3>& pictures) {
    for (int c = 0; c < 3; ++c) {
      if (c) ImGui::SameLine(static_cast<float>(c) * (w + 8));
      ImGui::Text("%s", titles[static_cast<std::size_t>(c)]);
    }
    for (int c = 0; c < 3; ++c) {
      if (c) ImGui::SameLine();
      pictures[static_cast<std::size_t>(c)]->Show(w);
    }
  };
  row({"camera edges", "virtual edges", "|camera - virtual|"},
      {&tex.camera_edges, &tex.virtual_edges, &tex.difference});
  row({"Harris corners (kept green)", "contour pieces", "matches (RANSAC inliers green)"},
      {&tex.corners, &tex.pieces, &tex.matches});
  ImGui::Text("Hough votes per corner");
  tex.votes.Show(avail);
  const MatchResult& m = p.last_feature_step().match;
  ImGui::Text(
      "%zu virtual corners, %zu Hough matches, %d RANSAC inliers (inhand match writes every "
      "stage)",
      m.debug.virtual_corners.size(), m.matches.size(), m.num_inliers());
}

ImU32 Im(const Rgb& c, int alpha = 255) { return IM_COL32(c.r, c.g, c.b, alpha); }

// The event nearest in time to the current one, before (`dir` < 0) or after it, of every set;
// contacts only when shown. Null when none.
const TrackerEvent* NextEvent(const GuiState& state, double t, int dir) {
  const TrackerEvent* best = nullptr;
  for (const auto& set : state.overview.sets)
    for (const TrackerEvent& e : set.events) {
      if (!state.timeline_contacts && IsContact(e)) continue;
      const bool beyond = dir < 0 ? e.t < t - 1e-6 : e.t > t + 1e-6;
      if (beyond && (!best || (dir < 0 ? e.t > best->t : e.t < best->t))) best = &e;
    }
  return best;
}

// The time window the timeline and the plots show: the whole session unless zoomed.
std::pair<double, double> TimeWindow(const Session& s, const GuiState& state) {
  const double t0 = s.t(0), t1 = std::max(s.t(s.num_samples() - 1), t0 + 1e-3);
  if (!(state.view_t0 < state.view_t1)) return {t0, t1};
  return {std::max(t0, state.view_t0), std::min(t1, state.view_t1)};
}

// Over the timeline or a plot (its time axis from x0 to x1 px): the wheel zooms the shared window
// about the time under the mouse, a right drag pans it, a double click shows the whole session.
void ZoomAndPan(const Session& s, GuiState& state, float x0, float x1) {
  const ImGuiIO& io = ImGui::GetIO();
  const auto [w0, w1] = TimeWindow(s, state);
  const double t0 = s.t(0), t1 = std::max(s.t(s.num_samples() - 1), t0 + 1e-3);
  const double per_px = (w1 - w0) / std::max(1.0f, x1 - x0);
  double a = w0, b = w1;
  if (io.MouseWheel != 0.0f) {
    const double at = w0 + (io.MousePos.x - x0) * per_px;
    const double scale = std::pow(0.8, io.MouseWheel);
    a = at - (at - w0) * scale, b = at + (w1 - at) * scale;
  }
  if (ImGui::IsMouseDragging(ImGuiMouseButton_Right)) {
    const double shift = -io.MouseDelta.x * per_px;
    a += shift, b += shift;
  }
  if (ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left)) a = t0, b = t1;
  if (a == w0 && b == w1) return;
  const double span = std::clamp(b - a, 0.01, t1 - t0);  // 10 ms at the most zoomed
  if (a < t0) a = t0;
  if (a + span > t1) a = t1 - span;
  state.view_t0 = a, state.view_t1 = a + span;
}

// Under the picture: a time axis, one lane per set with its health as a band (green ok, yellow
// uncertain, orange inconsistent, red lost) and a marker per event, the current time as a white
// line. Click or drag to seek, hover a marker for its message; [ and ] jump to the previous and
// next event. The events come from the overview, which may still be on its way.
void DrawTimeline(Runner& runner, GuiState& state, float width) {
  const Session& s = runner.session();
  const SessionPlayer& p = runner.player();
  const auto [t0, t1] = TimeWindow(s, state);
  const double session_end = s.t(s.num_samples() - 1);
  constexpr float kLabel = 40.0f, kAxis = 16.0f, kLane = 16.0f;
  const float height = kAxis + kLane * static_cast<float>(p.sets().size());
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImGui::InvisibleButton("timeline", ImVec2(width, height));
  const bool hovered = ImGui::IsItemHovered(), active = ImGui::IsItemActive();
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float x0 = origin.x + kLabel, x1 = origin.x + width - 4.0f;
  const auto x_of = [&](double t) {
    return x0 + static_cast<float>((t - t0) / (t1 - t0)) * (x1 - x0);
  };
  const auto t_of = [&](float x) {
    return std::clamp(t0 + (x - x0) / (x1 - x0) * (t1 - t0), t0, t1);
  };
  dl->AddRectFilled(origin, ImVec2(origin.x + width, origin.y + height), IM_COL32(22, 22, 28, 255));
  if (hovered) ZoomAndPan(s, state, x0, x1);
  dl->PushClipRect(origin, ImVec2(origin.x + width, origin.y + height), true);
  // The time axis.
  const double step = TickStep(t1 - t0, x1 - x0, 70.0f);
  for (double t = std::ceil(t0 / step - 1e-9) * step; t <= t1 + 1e-9; t += step) {
    const float x = x_of(t);
    dl->AddLine(ImVec2(x, origin.y + kAxis - 4), ImVec2(x, origin.y + height),
                IM_COL32(70, 70, 80, 255));
    char label[32];
    std::snprintf(label, sizeof label, "%g s", std::round(t / step) * step + 0.0);  // not -0
    if (x + 2 + ImGui::CalcTextSize(label).x <= origin.x + width)
      dl->AddText(ImVec2(x + 2, origin.y), IM_COL32(170, 170, 180, 255), label);
  }
  // One lane per set.
  const ImGuiIO& io = ImGui::GetIO();
  const TrackerEvent* under_mouse = nullptr;
  std::size_t under_set = 0;
  float under_dx = 5.0f;  // px: a marker this close is under the mouse
  const double known = state.overview.progress.done ? session_end : state.overview.progress.t;
  for (std::size_t i = 0; i < p.sets().size() && i < state.overview.sets.size(); ++i) {
    const float y = origin.y + kAxis + kLane * static_cast<float>(i);
    const Rgb& c = p.sets()[i].colour;
    dl->AddText(ImVec2(origin.x + 4, y), IM_COL32(c.r, c.g, c.b, state.Hidden(i) ? 90 : 255),
                p.sets()[i].name.c_str());
    if (state.Hidden(i)) continue;
    // The health band, from each change to the next.
    HealthState health = HealthState::kOk;
    double from = t0;
    const auto band = [&](double to) {
      const float a = std::max(x_of(from), x0), b = std::min(x_of(to), x1);
      if (a < b)
        dl->AddRectFilled(ImVec2(a, y + kLane - 5), ImVec2(b, y + kLane - 2),
                          Im(HealthColour(health)));
    };
    for (const TrackerEvent& e : state.overview.sets[i].events)
      if (e.kind == EventKind::kHealth) band(e.t), from = e.t, health = e.health.state;
    band(known);
    // The markers: contacts as thin ticks at the top, bursts as bars over their span, the rest as
    // dots.
    const float mid = y + kLane * 0.45f;
    for (const TrackerEvent& e : state.overview.sets[i].events) {
      if (e.kind == EventKind::kHealth) continue;
      if (!state.timeline_contacts && IsContact(e)) continue;
      const float x = x_of(e.t);
      if (x < x0 - 3 || x > x1 + 3) continue;  // outside the window
      const ImU32 colour = Im(EventColour(e));
      if (IsContact(e))
        dl->AddLine(ImVec2(x, y + 1), ImVec2(x, y + 6), colour);
      else if (e.duration > 0.0 && !IsContact(e))
        dl->AddRectFilled(ImVec2(x, mid - 3),
                          ImVec2(std::max(x + 3, x_of(e.t + e.duration)), mid + 3), colour);
      else
        dl->AddCircleFilled(ImVec2(x, mid), 3.5f, colour);
      if (hovered && io.MousePos.y >= y && io.MousePos.y < y + kLane &&
          std::abs(io.MousePos.x - x) < under_dx)
        under_mouse = &e, under_set = i, under_dx = std::abs(io.MousePos.x - x);
    }
    // And each health change as a small bar of its colour.
    for (const TrackerEvent& e : state.overview.sets[i].events) {
      if (e.kind != EventKind::kHealth) continue;
      const float x = x_of(e.t);
      if (x < x0 - 3 || x > x1 + 3) continue;
      dl->AddRectFilled(ImVec2(x - 1, y + kLane - 9), ImVec2(x + 1, y + kLane - 2),
                        Im(HealthColour(e.health.state)));
      if (hovered && io.MousePos.y >= y && io.MousePos.y < y + kLane &&
          std::abs(io.MousePos.x - x) < under_dx)
        under_mouse = &e, under_set = i, under_dx = std::abs(io.MousePos.x - x);
    }
  }
  // What is not known yet.
  if (!state.overview.progress.done && x_of(known) < x1) {
    const float from = std::max(x_of(known), x0);
    dl->AddRectFilled(ImVec2(from, origin.y + kAxis), ImVec2(origin.x + width, origin.y + height),
                      IM_COL32(0, 0, 0, 140));
    char text[64];
    std::snprintf(text, sizeof text, "finding events... %.0f%%",
                  state.overview.progress.share * 100);
    dl->AddText(ImVec2(from + 6, origin.y + kAxis + 2), IM_COL32(200, 200, 200, 255), text);
  } else if (!state.overview.progress.error.empty()) {
    dl->AddText(ImVec2(x0, origin.y + kAxis + 2), IM_COL32(255, 100, 100, 255),
                state.overview.progress.error.c_str());
  }
  // The current time.
  const float cursor = x_of(s.t(std::max(0, runner.sample())));
  if (cursor >= x0 - 1 && cursor <= x1 + 1)
    dl->AddLine(ImVec2(cursor, origin.y), ImVec2(cursor, origin.y + height),
                IM_COL32(255, 255, 255, 255), 2.0f);
  dl->PopClipRect();
  if (under_mouse) {
    ImGui::BeginTooltip();
    ImGui::Text("%.3f s  %s  %s", under_mouse->t, p.sets()[under_set].name.c_str(),
                EventKindName(under_mouse->kind));
    ImGui::TextUnformatted(EventMessage(*under_mouse, p.models().hand).c_str());
    ImGui::EndTooltip();
  }
  // Click a marker: to its time; click or drag elsewhere: to the time under the mouse.
  if (active && io.MousePos.x >= x0 - 2) {
    const double t = under_mouse && ImGui::IsMouseClicked(ImGuiMouseButton_Left)
                         ? under_mouse->t
                         : t_of(io.MousePos.x);
    const int k = runner.SampleAt(t);
    if (k != runner.sample()) state.actions.push_back({ActionKind::kSeek, k});
  }
}

// One quantity of every set over the shared time window, from the overview: value and time axes
// with ticks and labels, the unit, a legend in the sets' colours, an optional band (NEES's χ²
// interval) and threshold line, the current time, a read-out of every set under the mouse; click
// to seek, wheel and right drag to zoom and pan (ZoomAndPan). `cap`: values above it are drawn at
// it (the axis says so). Each pixel column draws its samples' minimum and maximum, so a long
// session costs the window's width, not its samples.
// One of a set's series in the overview.
using Series = std::function<const std::vector<float>&(const SessionOverview::Set&)>;
Series Member(std::vector<float> SessionOverview::Set::*m) {
  return [m](const SessionOverview::Set& s) -> const std::vector<float>& { return s.*m; };
}
Series Axis(std::array<std::vector<float>, 3> SessionOverview::Set::*m, int axis) {
  return [m, axis](const SessionOverview::Set& s) -> const std::vector<float>& {
    return (s.*m)[static_cast<std::size_t>(axis)];
  };
}
// One of a per-joint or per-link list of series (empty where the set has no such entry).
Series Element(std::vector<std::vector<float>> SessionOverview::Set::*m, std::size_t index) {
  return [m, index](const SessionOverview::Set& s) -> const std::vector<float>& {
    static const std::vector<float> kNone;
    return index < (s.*m).size() ? (s.*m)[index] : kNone;
  };
}

struct PlotSpec {
  const char* id;
  std::string title;
  const char* unit;
  Series series;
  double band_lo = NAN, band_hi = NAN;  // a shaded band
  double line = NAN;                    // a dashed threshold
  double cap = NAN;
  Series envelope = nullptr;  // drawn as ± this about zero, faint, in each set's colour
  const SessionOverview::Data* data = nullptr;  // null: the overview (A)
};

void DrawPlotInside(Runner& runner, GuiState& state, const PlotSpec& spec, ImVec2 size);

void DrawPlot(Runner& runner, GuiState& state, const PlotSpec& spec, ImVec2 size) {
  // A child window of its own: its draw list stays within ImGui's 16-bit vertex indices.
  ImGui::BeginChild(spec.id, size, false,
                    ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoScrollWithMouse);
  DrawPlotInside(runner, state, spec, size);
  ImGui::EndChild();
}

// Plots side by side, `per_row` to a row across `avail` pixels, each `height` tall.
void DrawPlots(Runner& runner, GuiState& state, const std::vector<PlotSpec>& plots, int per_row,
               float avail, float height) {
  const float spacing = ImGui::GetStyle().ItemSpacing.x;
  const ImVec2 size(
      (avail - static_cast<float>(per_row - 1) * spacing) / static_cast<float>(per_row), height);
  for (std::size_t i = 0; i < plots.size(); ++i) {
    if (i % static_cast<std::size_t>(per_row)) ImGui::SameLine();
    DrawPlot(runner, state, plots[i], size);
  }
}

void DrawPlotInside(Runner& runner, GuiState& state, const PlotSpec& spec, ImVec2 size) {
  const Session& s = runner.session();
  const SessionPlayer& p = runner.player();
  const SessionOverview::Data& data = spec.data ? *spec.data : state.overview;
  constexpr float kLeft = 52.0f, kTop = 18.0f, kBottom = 16.0f, kRight = 6.0f;
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImGui::InvisibleButton("plot", size);
  const bool hovered = ImGui::IsItemHovered(), active = ImGui::IsItemActive();
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float x0 = origin.x + kLeft, x1 = origin.x + size.x - kRight;
  const float y0 = origin.y + kTop, y1 = origin.y + size.y - kBottom;
  if (hovered) ZoomAndPan(s, state, x0, x1);
  const auto [w0, w1] = TimeWindow(s, state);
  const auto x_of = [&](double t) {
    return x0 + static_cast<float>((t - w0) / (w1 - w0)) * (x1 - x0);
  };
  dl->AddRectFilled(origin, ImVec2(origin.x + size.x, origin.y + size.y),
                    IM_COL32(22, 22, 28, 255));
  dl->AddRectFilled(ImVec2(x0, y0), ImVec2(x1, y1), IM_COL32(30, 32, 42, 255));
  // The samples in the window, and the value range over them.
  const auto first = std::lower_bound(data.t.begin(), data.t.end(), w0);
  const auto last = std::upper_bound(data.t.begin(), data.t.end(), w1);
  const std::size_t a = static_cast<std::size_t>(first - data.t.begin()),
                    b = static_cast<std::size_t>(last - data.t.begin());
  double lo = 0.0, hi = 0.0;
  for (std::size_t i = 0; i < data.sets.size(); ++i) {
    if (state.Hidden(i)) continue;
    const std::vector<float>& y = spec.series(data.sets[i]);
    for (std::size_t k = a; k < b && k < y.size(); ++k) {
      const double v = y[k];
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    }
    if (!spec.envelope) continue;
    const std::vector<float>& e = spec.envelope(data.sets[i]);
    for (std::size_t k = a; k < b && k < e.size(); ++k) {
      const double v = e[k];
      if (std::isfinite(v)) lo = std::min(lo, -v), hi = std::max(hi, v);
    }
  }
  if (std::isfinite(spec.line)) hi = std::max(hi, spec.line);
  if (std::isfinite(spec.band_hi)) hi = std::max(hi, spec.band_hi);
  const bool capped = std::isfinite(spec.cap) && hi > spec.cap;
  if (capped) hi = spec.cap;
  hi = hi > lo ? hi + 0.05 * (hi - lo) : lo + 1.0;
  const auto y_of = [&](double v) {
    return y1 - static_cast<float>((std::min(v, hi) - lo) / (hi - lo)) * (y1 - y0);
  };
  // Axes: value ticks with labels, time ticks with labels.
  const ImU32 grid = IM_COL32(60, 62, 75, 255), text = IM_COL32(170, 170, 180, 255);
  const double vstep = TickStep(hi - lo, y1 - y0, 22.0f);
  for (double v = std::ceil(lo / vstep - 1e-9) * vstep; v <= hi + 1e-12; v += vstep) {
    const float y = y_of(v);
    dl->AddLine(ImVec2(x0, y), ImVec2(x1, y), grid);
    char label[32];
    std::snprintf(label, sizeof label, "%g", std::round(v / vstep) * vstep + 0.0);  // not -0
    const float w = ImGui::CalcTextSize(label).x;
    dl->AddText(ImVec2(x0 - 4 - w, y - 7), text, label);
  }
  const double tstep = TickStep(w1 - w0, x1 - x0, 70.0f);
  for (double t = std::ceil(w0 / tstep - 1e-9) * tstep; t <= w1 + 1e-9; t += tstep) {
    const float x = x_of(t);
    dl->AddLine(ImVec2(x, y0), ImVec2(x, y1 + 3), grid);
    char label[32];
    std::snprintf(label, sizeof label, "%g s", std::round(t / tstep) * tstep + 0.0);
    if (x + ImGui::CalcTextSize(label).x <= origin.x + size.x)
      dl->AddText(ImVec2(x + 2, y1 + 1), text, label);
  }
  // The title, the unit and the legend.
  char title[160];
  std::snprintf(title, sizeof title, "%s%s%s%s%s", spec.title.c_str(), *spec.unit ? " [" : "",
                spec.unit, *spec.unit ? "]" : "", capped ? " (top clipped)" : "");
  dl->AddText(ImVec2(x0, origin.y + 1), IM_COL32(220, 220, 230, 255), title);
  float lx = x0 + ImGui::CalcTextSize(title).x + 14;
  for (std::size_t i = 0; i < p.sets().size(); ++i) {
    const Rgb& c = p.sets()[i].colour;
    const char* name = p.sets()[i].name.c_str();
    if (lx + ImGui::CalcTextSize(name).x > x1) break;  // no room left
    dl->AddText(ImVec2(lx, origin.y + 1), IM_COL32(c.r, c.g, c.b, state.Hidden(i) ? 90 : 255),
                name);
    lx += ImGui::CalcTextSize(name).x + 10;
  }
  dl->PushClipRect(ImVec2(x0, y0), ImVec2(x1, y1), true);
  if (std::isfinite(spec.band_lo))
    dl->AddRectFilled(ImVec2(x0, y_of(spec.band_hi)), ImVec2(x1, y_of(spec.band_lo)),
                      IM_COL32(80, 160, 90, 50));
  if (std::isfinite(spec.line))
    for (float x = x0; x < x1; x += 8)
      dl->AddLine(ImVec2(x, y_of(spec.line)), ImVec2(std::min(x + 4, x1), y_of(spec.line)),
                  IM_COL32(230, 120, 120, 200));
  // Every set: per pixel column, its samples' minimum and maximum.
  std::vector<ImVec2> points;
  for (std::size_t i = 0; i < data.sets.size() && i < p.sets().size(); ++i) {
    if (state.Hidden(i)) continue;
    const Rgb& c = p.sets()[i].colour;
    if (spec.envelope) {  // ±σ: thin and faint, per pixel column its largest
      const std::vector<float>& e = spec.envelope(data.sets[i]);
      for (const float sign : {1.0f, -1.0f}) {
        points.clear();
        int column = -1;
        for (std::size_t k = a; k < std::min(b, e.size()); ++k) {
          const int col = static_cast<int>(std::floor(x_of(data.t[k]) - x0));
          const float y = y_of(sign * e[k]);
          if (col != column)
            points.emplace_back(x0 + static_cast<float>(col), y), column = col;
          else if (sign * (points.back().y - y) > 0)  // farther from zero
            points.back().y = y;
        }
        if (points.size() > 1)
          dl->AddPolyline(points.data(), static_cast<int>(points.size()),
                          IM_COL32(c.r, c.g, c.b, 120), 0, 1.0f);
      }
    }
    const std::vector<float>& y = spec.series(data.sets[i]);
    points.clear();
    int column = -1;
    float cmin = 0, cmax = 0;
    const auto flush = [&] {
      if (column < 0) return;
      const float x = x0 + static_cast<float>(column);
      points.emplace_back(x, y_of(cmax));
      if (cmin != cmax) points.emplace_back(x, y_of(cmin));
    };
    const std::size_t from = a > 0 ? a - 1 : a, to = std::min(b + 1, y.size());
    for (std::size_t k = from; k < to; ++k) {
      const float v = y[k];
      if (!std::isfinite(v)) {  // a gap (no truth there)
        flush(), column = -1;
        if (points.size() > 1)
          dl->AddPolyline(points.data(), static_cast<int>(points.size()),
                          IM_COL32(c.r, c.g, c.b, 255), 0, 1.5f);
        points.clear();
        continue;
      }
      const int col = static_cast<int>(std::floor(x_of(data.t[k]) - x0));
      if (col != column) {
        flush();
        column = col, cmin = cmax = v;
      } else {
        cmin = std::min(cmin, v), cmax = std::max(cmax, v);
      }
    }
    flush();
    if (points.size() > 1)
      dl->AddPolyline(points.data(), static_cast<int>(points.size()), IM_COL32(c.r, c.g, c.b, 255),
                      0, 1.5f);
  }
  // What is not known yet, and the current time.
  const double known = data.progress.done ? s.t(s.num_samples() - 1) : data.progress.t;
  if (!data.progress.done && x_of(known) < x1)
    dl->AddRectFilled(ImVec2(std::max(x0, x_of(known)), y0), ImVec2(x1, y1),
                      IM_COL32(0, 0, 0, 120));
  const float cursor = x_of(s.t(std::max(0, runner.sample())));
  dl->AddLine(ImVec2(cursor, y0), ImVec2(cursor, y1), IM_COL32(255, 255, 255, 255), 1.5f);
  dl->PopClipRect();
  // The read-out under the mouse, and a click to seek.
  const ImGuiIO& io = ImGui::GetIO();
  if (hovered && io.MousePos.x >= x0 && io.MousePos.x <= x1 && !data.t.empty()) {
    const double t = w0 + (io.MousePos.x - x0) / (x1 - x0) * (w1 - w0);
    const std::size_t k = std::min<std::size_t>(
        static_cast<std::size_t>(std::lower_bound(data.t.begin(), data.t.end(), t) -
                                 data.t.begin()),
        data.t.size() - 1);
    dl->AddLine(ImVec2(io.MousePos.x, y0), ImVec2(io.MousePos.x, y1), IM_COL32(200, 200, 200, 90));
    ImGui::BeginTooltip();
    ImGui::Text("%.3f s", data.t[k]);
    for (std::size_t i = 0; i < data.sets.size() && i < p.sets().size(); ++i) {
      if (state.Hidden(i)) continue;
      const std::vector<float>& y = spec.series(data.sets[i]);
      const Rgb& c = p.sets()[i].colour;
      if (spec.envelope) {
        const std::vector<float>& e = spec.envelope(data.sets[i]);
        ImGui::TextColored(ImVec4(c.r / 255.f, c.g / 255.f, c.b / 255.f, 1.f),
                           "%-4s %.3g %s (sigma %.3g)", p.sets()[i].name.c_str(),
                           k < y.size() ? y[k] : NAN, spec.unit, k < e.size() ? e[k] : NAN);
        continue;
      }
      ImGui::TextColored(ImVec4(c.r / 255.f, c.g / 255.f, c.b / 255.f, 1.f), "%-4s %.3g %s",
                         p.sets()[i].name.c_str(), k < y.size() ? y[k] : NAN, spec.unit);
    }
    ImGui::EndTooltip();
    if (active && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
      const int sample = runner.SampleAt(t);
      if (sample != runner.sample()) state.actions.push_back({ActionKind::kSeek, sample});
    }
  }
}

// The errors against the truth, the estimates' σ, their consistency and their impossibility,
// every set in one plot per quantity, over the shared time window.
void DrawErrorPlots(Runner& runner, GuiState& state, float avail) {
  using Set = SessionOverview::Set;
  const bool truth = runner.session().has_groundtruth();
  // The errors and σ as norms and largest axes, or signed along one axis of the object frame with
  // ±σ about them.
  const char* axes[] = {"norm / largest axis", "object x", "object y", "object z"};
  ImGui::SetNextItemWidth(180);
  ImGui::Combo("errors and sigma", &state.error_axis, axes, 4);
  const int a = state.error_axis - 1;
  std::vector<PlotSpec> plots;
  if (a < 0) {
    if (truth) {
      plots.push_back({"##pe", "position error", "mm", Member(&Set::position_error)});
      plots.push_back({"##oe", "orientation error", "deg", Member(&Set::orientation_error)});
    }
    plots.push_back({"##sp", "position sigma, largest axis", "mm", Member(&Set::sigma_position)});
    plots.push_back(
        {"##so", "orientation sigma, largest axis", "deg", Member(&Set::sigma_orientation)});
  } else {
    const std::string along = std::string(", ") + axes[state.error_axis];
    const std::string about = along;
    if (truth) {
      plots.push_back({"##pe", "position error" + along + " (faint: +-sigma)", "mm",
                       Axis(&Set::position_error_axis, a)});
      plots.back().envelope = Axis(&Set::sigma_position_axis, a);
      plots.push_back({"##oe", "orientation error" + about + " (faint: +-sigma)", "deg",
                       Axis(&Set::orientation_error_axis, a)});
      plots.back().envelope = Axis(&Set::sigma_orientation_axis, a);
    }
    plots.push_back({"##sp", "position sigma" + along, "mm", Axis(&Set::sigma_position_axis, a)});
    plots.push_back(
        {"##so", "orientation sigma" + about, "deg", Axis(&Set::sigma_orientation_axis, a)});
  }
  if (truth)
    plots.push_back({"##nees", "NEES, chi2(6) 95% band, 99% line", "", Member(&Set::nees), 1.237,
                     14.449, 16.812, 60.0});
  plots.push_back({"##pen", "deepest link inside the estimate (5 mm: inconsistent)", "mm",
                   Member(&Set::penetration), NAN, NAN, state.params.health.penetration * 1000});
  DrawPlots(runner, state, plots, 2, avail, 104);
  if (!truth) ImGui::TextUnformatted("no ground truth: errors and NEES are not known");
}

// A joint's bias with its σ, and what each set fused and refused, every set in one plot per
// quantity, over the shared window.
void DrawCountPlots(Runner& runner, GuiState& state, float avail) {
  using Set = SessionOverview::Set;
  const std::vector<std::string> joints = runner.player().models().hand.QNames();
  state.bias_joint = std::clamp(state.bias_joint, 0, static_cast<int>(joints.size()) - 1);
  ImGui::SetNextItemWidth(180);
  if (ImGui::BeginCombo("joint",
                        joints.empty() ? "" : joints[std::size_t(state.bias_joint)].c_str())) {
    for (int j = 0; j < static_cast<int>(joints.size()); ++j)
      if (ImGui::Selectable(joints[static_cast<std::size_t>(j)].c_str(), j == state.bias_joint))
        state.bias_joint = j;
    ImGui::EndCombo();
  }
  const std::size_t j = static_cast<std::size_t>(state.bias_joint);
  std::vector<PlotSpec> plots = {
      {"##bias", "bias of " + (joints.empty() ? std::string() : joints[j]) + " (faint: +-sigma)",
       "deg", Element(&Set::bias, j)},
      {"##force", "contact forces from the torques, summed", "N", Member(&Set::contact_force)},
      {"##constraints", "contact constraints applied", "", Member(&Set::constraints)},
      {"##gated", "measurements gated (contacts, vision)", "", Member(&Set::gated)},
      {"##cinnovation", "contacts: mean Mahalanobis distance of the constraints", "",
       Member(&Set::contact_mahalanobis)},
      {"##innovation", "vision: mean Mahalanobis distance of the last image", "",
       Member(&Set::visual_mahalanobis)},
      {"##unexplained", "joint torque the contacts leave unexplained", "N m",
       Member(&Set::unexplained_torque)}};
  plots.front().envelope = Element(&Set::sigma_bias, j);
  DrawPlots(runner, state, plots, 2, avail, 104);
}

// The inspector's colours of a link's contact status (ContactStatus): nothing, a candidate, a
// rejected torque candidate, a fused kinematic or torque constraint, a gated one.
ImU32 StatusColour(ContactStatus s) {
  switch (s) {
    case ContactStatus::kNone:
      return IM_COL32(30, 32, 42, 255);
    case ContactStatus::kCandidate:
      return IM_COL32(105, 105, 115, 255);
    case ContactStatus::kRejected:
      return IM_COL32(190, 80, 200, 255);
    case ContactStatus::kKinematic:
      return IM_COL32(70, 140, 240, 255);
    case ContactStatus::kTorque:
      return IM_COL32(60, 200, 90, 255);
    case ContactStatus::kGated:
      return IM_COL32(235, 60, 50, 255);
  }
  return IM_COL32(0, 0, 0, 255);
}

// The selected link's status over the shared window, one lane per set: per pixel column the most
// telling status of its samples (ContactStatus's order); the cursor; a click seeks.
void DrawStatusLanes(Runner& runner, GuiState& state, std::size_t link, float width) {
  const Session& s = runner.session();
  const SessionPlayer& p = runner.player();
  const SessionOverview::Data& data = state.overview;
  constexpr float kLeft = 52.0f, kRight = 6.0f, kLane = 12.0f, kLegend = 16.0f;
  const float height = kLegend + kLane * static_cast<float>(p.sets().size());
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImGui::InvisibleButton("status lanes", ImVec2(width, height));
  const bool hovered = ImGui::IsItemHovered(), active = ImGui::IsItemActive();
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float x0 = origin.x + kLeft, x1 = origin.x + width - kRight;
  if (hovered) ZoomAndPan(s, state, x0, x1);
  const auto [w0, w1] = TimeWindow(s, state);
  const auto x_of = [&](double t) {
    return x0 + static_cast<float>((t - w0) / (w1 - w0)) * (x1 - x0);
  };
  dl->AddRectFilled(origin, ImVec2(origin.x + width, origin.y + height), IM_COL32(22, 22, 28, 255));
  float lx = x0;
  for (int k = 1; k <= static_cast<int>(ContactStatus::kGated); ++k) {
    const ContactStatus status = static_cast<ContactStatus>(k);
    dl->AddRectFilled(ImVec2(lx, origin.y + 4), ImVec2(lx + 9, origin.y + 13),
                      StatusColour(status));
    dl->AddText(ImVec2(lx + 12, origin.y), IM_COL32(200, 200, 210, 255), ContactStatusName(status));
    lx += 24 + ImGui::CalcTextSize(ContactStatusName(status)).x;
  }
  const auto first = std::lower_bound(data.t.begin(), data.t.end(), w0);
  const auto last = std::upper_bound(data.t.begin(), data.t.end(), w1);
  const std::size_t a = static_cast<std::size_t>(first - data.t.begin()),
                    b = static_cast<std::size_t>(last - data.t.begin());
  for (std::size_t i = 0; i < p.sets().size() && i < data.sets.size(); ++i) {
    const float y = origin.y + kLegend + kLane * static_cast<float>(i);
    const Rgb& c = p.sets()[i].colour;
    dl->AddText(ImVec2(origin.x + 4, y - 2), IM_COL32(c.r, c.g, c.b, state.Hidden(i) ? 90 : 255),
                p.sets()[i].name.c_str());
    dl->AddRectFilled(ImVec2(x0, y + 1), ImVec2(x1, y + kLane - 1),
                      StatusColour(ContactStatus::kNone));
    if (link >= data.sets[i].link_status.size()) continue;
    const std::vector<std::uint8_t>& status = data.sets[i].link_status[link];
    int column = -1, worst = 0;
    const auto flush = [&] {
      if (column >= 0 && worst > 0) {
        const float x = x0 + static_cast<float>(column);
        dl->AddRectFilled(ImVec2(x, y + 1), ImVec2(x + 1, y + kLane - 1),
                          StatusColour(static_cast<ContactStatus>(worst)));
      }
    };
    for (std::size_t k = a; k < std::min(b, status.size()); ++k) {
      const int col = static_cast<int>(std::floor(x_of(data.t[k]) - x0));
      const int v = static_cast<int>(status[k]);
      if (col != column)
        flush(), column = col, worst = v;
      else
        worst = std::max(worst, v);
    }
    flush();
  }
  const float cursor = x_of(s.t(std::max(0, runner.sample())));
  if (cursor >= x0 && cursor <= x1)
    dl->AddLine(ImVec2(cursor, origin.y + kLegend), ImVec2(cursor, origin.y + height),
                IM_COL32(255, 255, 255, 255), 1.5f);
  const ImGuiIO& io = ImGui::GetIO();
  if (active && ImGui::IsMouseDown(ImGuiMouseButton_Left) && io.MousePos.x >= x0 &&
      io.MousePos.x <= x1) {
    const int sample = runner.SampleAt(w0 + (io.MousePos.x - x0) / (x1 - x0) * (w1 - w0));
    if (sample != runner.sample()) state.actions.push_back({ActionKind::kSeek, sample});
  }
}

// A visual measurement's name: a tag's corner (id = tag * 4 + corner) or a feature match.
std::string VisualName(const ModalitySet& set, int id) {
  char name[48];
  if (set.tags && !set.features)
    std::snprintf(name, sizeof name, "tag %d corner %d", id / 4, id % 4);
  else
    std::snprintf(name, sizeof name, "match %d", id);
  return name;
}

// The selected visual measurement's history over the shared window, in every set whose ids are
// stable: its residual and Mahalanobis distance (against the gate) in the last image fused at
// each time, gaps where that image did not measure it.
void DrawVisualHistory(Runner& runner, GuiState& state, std::size_t set, float avail) {
  const SessionPlayer& p = runner.player();
  if (!StableVisualIds(p.sets()[set])) {
    ImGui::TextWrapped(
        "%s matches its features afresh in each image: a match has no history (tag corners do)",
        p.sets()[set].name.c_str());
    return;
  }
  const std::string name = VisualName(p.sets()[set], state.inspect_visual);
  ImGui::TextWrapped(
      "%s over the shared window, in the last image fused at each time (gaps: not measured): %s",
      name.c_str(), VisualHistoryCounts(runner, state).c_str());
  using Set = SessionOverview::Set;
  std::vector<PlotSpec> plots = {
      {"##vresidual", "residual before the update", "px", &Set::visual_residual},
      {"##vmahalanobis", "Mahalanobis", "", &Set::visual_history_mahalanobis}};
  for (PlotSpec& plot : plots) plot.data = &state.visual_history;
  if (state.params.filter.visual_gate_chi2 > 0)
    plots[1].line = state.params.filter.visual_gate_chi2;
  DrawPlots(runner, state, plots, 2, avail, 104);
}

// Every measurement of one set's last step — each link's contact and each visual measurement of
// the image fused at it — in tables; a click on a row selects it (ringed in every view). For a
// selected link, its history over the shared window, every set: status lanes, signed distance,
// force from the torques, the Mahalanobis distance of its constraint against the gate.
void DrawInspector(Runner& runner, GuiState& state, const Textures& tex, float avail) {
  const SessionPlayer& p = runner.player();
  const HandModel& hand = p.models().hand;
  const std::size_t set = InspectedSet(runner, state);
  ImGui::SetNextItemWidth(120);
  if (ImGui::BeginCombo("set", p.sets()[set].name.c_str())) {
    for (std::size_t i = 0; i < p.sets().size(); ++i)
      if (ImGui::Selectable(p.sets()[i].name.c_str(), i == set))
        state.inspect_set = static_cast<int>(i), state.pictures_dirty = true;
    ImGui::EndCombo();
  }
  const FilterTrace& trace = p.tracker(set).filter().trace();
  static std::vector<LinkContact> links;
  LinkContacts(trace, hand.links.size(), links);
  const std::vector<FilterTrace::Visual>& visual = runner.visual(set);
  ImGui::SameLine();
  if (std::isnan(runner.visual_t(set)))
    ImGui::Text("its step at %.3f s: %d constraints applied, %d gated",
                runner.session().t(std::max(0, runner.sample())), trace.num_constraints,
                trace.num_gated);
  else
    ImGui::Text("its step at %.3f s: %d constraints applied, %d gated; its last image at %.3f s",
                runner.session().t(std::max(0, runner.sample())), trace.num_constraints,
                trace.num_gated, runner.visual_t(set));
  const double gate = state.params.filter.contact_gate_chi2;
  const float table_height = std::min(150.0f, ImGui::GetContentRegionAvail().y * 0.4f);
  const ImGuiTableFlags flags = ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg |
                                ImGuiTableFlags_ScrollY | ImGuiTableFlags_SizingStretchProp;
  const float half = (avail - ImGui::GetStyle().ItemSpacing.x) / 2;
  if (ImGui::BeginTable("contacts", 5, flags, ImVec2(half, table_height))) {
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("link");
    ImGui::TableSetupColumn("status");
    ImGui::TableSetupColumn("distance mm");
    ImGui::TableSetupColumn("force N");
    ImGui::TableSetupColumn(gate > 0 ? "Mahalanobis / gate" : "Mahalanobis");
    ImGui::TableHeadersRow();
    for (std::size_t l = 0; l < links.size(); ++l) {
      const LinkContact& c = links[l];
      if (c.status == ContactStatus::kNone) continue;
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::PushID(static_cast<int>(l));
      const bool selected = state.inspect_link == static_cast<int>(l);
      if (ImGui::Selectable(hand.links[l].name.c_str(), selected,
                            ImGuiSelectableFlags_SpanAllColumns)) {
        state.inspect_set = static_cast<int>(set);
        state.inspect_link = static_cast<int>(l), state.inspect_visual = -1;
        state.pictures_dirty = true;
      }
      ImGui::PopID();
      ImGui::TableNextColumn();
      ImGui::TextColored(ImGui::ColorConvertU32ToFloat4(StatusColour(c.status)), "%s",
                         ContactStatusName(c.status));
      ImGui::TableNextColumn();
      ImGui::Text("%.2f", c.distance * 1000);
      ImGui::TableNextColumn();
      ImGui::Text(c.force > 0 ? "%.2f" : "-", c.force);
      ImGui::TableNextColumn();
      if (std::isnan(c.mahalanobis))
        ImGui::TextUnformatted("-");
      else if (gate > 0)
        ImGui::Text("%.2f / %.2f", c.mahalanobis, gate);
      else
        ImGui::Text("%.2f", c.mahalanobis);
    }
    ImGui::EndTable();
  }
  ImGui::SameLine();
  if (ImGui::BeginTable("visual", 5, flags, ImVec2(half, table_height))) {
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("measurement");
    ImGui::TableSetupColumn("measured px");
    ImGui::TableSetupColumn("residual px");
    ImGui::TableSetupColumn("Mahalanobis");
    ImGui::TableSetupColumn("fused");
    ImGui::TableHeadersRow();
    for (const FilterTrace::Visual& v : visual) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::PushID(v.id);
      if (ImGui::Selectable(VisualName(p.sets()[set], v.id).c_str(), state.inspect_visual == v.id,
                            ImGuiSelectableFlags_SpanAllColumns)) {
        state.inspect_set = static_cast<int>(set);
        state.inspect_visual = v.id, state.inspect_link = -1;
        state.pictures_dirty = true;
      }
      ImGui::PopID();
      ImGui::TableNextColumn();
      ImGui::Text("%.1f, %.1f", v.measured.x(), v.measured.y());
      ImGui::TableNextColumn();
      ImGui::Text("%.2f", (v.measured - v.predicted).norm());
      ImGui::TableNextColumn();
      ImGui::Text("%.2f", v.mahalanobis);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(v.gated ? "gated" : "fused");
    }
    ImGui::EndTable();
  }
  for (const FilterTrace::Visual& v : visual) {
    if (v.id != state.inspect_visual) continue;
    const Vec2 r = v.measured - v.predicted;
    ImGui::TextWrapped(
        "%s of the image at %.3f s: measured (%.1f, %.1f) px, predicted at the estimate "
        "before the update (%.1f, %.1f) px, residual (%.2f, %.2f) px; Mahalanobis %.2f "
        "against the gate %.2f: %s",
        VisualName(p.sets()[set], v.id).c_str(), runner.visual_t(set), v.measured.x(),
        v.measured.y(), v.predicted.x(), v.predicted.y(), r.x(), r.y(), v.mahalanobis,
        state.params.filter.visual_gate_chi2, v.gated ? "gated" : "fused");
    // The patches, and the history beside them.
    const float x0 = ImGui::GetCursorPosX();
    bool beside = false;
    if (tex.has_patch_camera) {
      ImGui::BeginGroup();
      ImGui::TextUnformatted("camera (measured)");
      tex.patch_camera.Show(150);
      ImGui::EndGroup();
      beside = true;
    }
    if (tex.has_patch_virtual) {
      ImGui::SameLine();
      ImGui::BeginGroup();
      ImGui::TextUnformatted("virtual (predicted)");
      tex.patch_virtual.Show(150);
      ImGui::EndGroup();
    }
    if (beside) ImGui::SameLine();
    const float used = ImGui::GetCursorPosX() - x0;
    ImGui::BeginGroup();
    ImGui::PushTextWrapPos(ImGui::GetCursorPosX() + avail - used);
    DrawVisualHistory(runner, state, set, avail - used);
    ImGui::PopTextWrapPos();
    ImGui::EndGroup();
    return;
  }
  if (state.inspect_link < 0 || static_cast<std::size_t>(state.inspect_link) >= links.size()) {
    ImGui::TextUnformatted(
        "click a row: a link's history, a visual measurement's pixels; the selection is ringed "
        "in yellow in the views");
    return;
  }
  using Set = SessionOverview::Set;
  const std::size_t l = static_cast<std::size_t>(state.inspect_link);
  const std::string name = hand.links[l].name;
  ImGui::Text("%s in every set (the lanes and plots share the timeline's window; click to seek)",
              name.c_str());
  DrawStatusLanes(runner, state, l, avail);
  std::vector<PlotSpec> plots = {
      {"##ldistance", "signed distance", "mm", Element(&Set::link_distance, l)},
      {"##lforce", "force from torques", "N", Element(&Set::link_force, l)},
      {"##lmahalanobis", "Mahalanobis", "", Element(&Set::link_mahalanobis, l)}};
  plots[0].line = 0.0;
  if (gate > 0) plots[2].line = gate;
  DrawPlots(runner, state, plots, 3, avail, 104);
}

// What the Compare tab can set side by side: one per-sample series of each set.
struct CompareQuantity {
  const char* name;  // the script's word
  const char* title;
  const char* unit;
  std::vector<float> SessionOverview::Set::*series;
  bool truth;  // needs ground truth
};
constexpr CompareQuantity kCompareQuantities[] = {
    {"position_error", "position error", "mm", &SessionOverview::Set::position_error, true},
    {"orientation_error", "orientation error", "deg", &SessionOverview::Set::orientation_error,
     true},
    {"sigma_position", "position sigma, largest axis", "mm", &SessionOverview::Set::sigma_position,
     false},
    {"sigma_orientation", "orientation sigma, largest axis", "deg",
     &SessionOverview::Set::sigma_orientation, false},
    {"nees", "NEES", "", &SessionOverview::Set::nees, true},
    {"penetration", "deepest link inside the estimate", "mm", &SessionOverview::Set::penetration,
     false},
};
constexpr int kNumCompareQuantities = sizeof kCompareQuantities / sizeof kCompareQuantities[0];

// B − A of one series, sample by sample over the samples both have replayed, into `out` (its
// progress B's while B runs, so that the plot shades what is not known yet).
void CompareDifference(const SessionOverview::Data& a, const SessionOverview::Data& b,
                       std::vector<float> SessionOverview::Set::*m, SessionOverview::Data& out) {
  const std::size_t n = std::min(a.t.size(), b.t.size());
  out.t.assign(a.t.begin(), a.t.begin() + static_cast<long>(n));
  out.progress = b.progress.done ? a.progress : b.progress;
  if (!a.progress.done && a.progress.t < out.progress.t) out.progress = a.progress;
  out.sets.resize(std::min(a.sets.size(), b.sets.size()));
  for (std::size_t i = 0; i < out.sets.size(); ++i) {
    const std::vector<float>&x = a.sets[i].*m, &y = b.sets[i].*m;
    std::vector<float>& d = out.sets[i].*m;
    d.resize(std::min({n, x.size(), y.size()}));
    for (std::size_t k = 0; k < d.size(); ++k) d[k] = y[k] - x[k];
  }
}

// The largest |B − A| of set i's series (NaN where either is NaN: left out; 0 when nothing is
// known).
double LargestDifference(const SessionOverview::Data& diff, std::size_t i,
                         std::vector<float> SessionOverview::Set::*m) {
  double worst = 0.0;
  if (i < diff.sets.size())
    for (const float v : diff.sets[i].*m)
      if (std::isfinite(v)) worst = std::max(worst, static_cast<double>(std::abs(v)));
  return worst;
}

// A's and B's mean of a series over the samples both have, each over its finite values.
std::pair<double, double> CompareMeans(const SessionOverview::Data& a,
                                       const SessionOverview::Data& b, std::size_t i,
                                       std::vector<float> SessionOverview::Set::*m) {
  const std::size_t n = std::min(a.t.size(), b.t.size());
  const auto mean = [n, i, m](const SessionOverview::Data& d) {
    double sum = 0.0;
    long count = 0;
    if (i < d.sets.size())
      for (std::size_t k = 0; k < std::min(n, (d.sets[i].*m).size()); ++k)
        if (std::isfinite((d.sets[i].*m)[k])) sum += (d.sets[i].*m)[k], ++count;
    return count ? sum / count : NAN;
  };
  return {mean(a), mean(b)};
}

// A/B: the session as the views show it (A) beside a replay with other parameters (B: the
// panel's, or a file's), with B's progress while it runs in the background; per set, the means of
// the chosen quantity and the largest difference; plots of A, of B and of B − A over the shared
// window.
void DrawCompare(Runner& runner, GuiState& state, float avail) {
  const SessionPlayer& p = runner.player();
  if (!runner.compare()) {
    ImGui::TextWrapped(
        "Replays the whole session again in the background with other parameters (B) and sets "
        "it beside what the views show (A). Edit the parameters in the panel and press "
        "'Compare: these', or name a parameter file (as 'Save parameters' writes and replay "
        "--params reads) and press 'Compare: the file'.");
    return;
  }
  const SessionOverview::Data &a = state.overview, &b = state.compare;
  if (!b.progress.error.empty()) {
    ImGui::TextWrapped("B failed: %s", b.progress.error.c_str());
    return;
  }
  ImGui::Text("A: the parameters the views show. B: %s. B replayed %.0f %% (to %.2f s)%s",
              state.compare_what.c_str(), 100 * b.progress.share, b.progress.t,
              b.progress.done ? ", done" : "...");
  const bool truth = runner.session().has_groundtruth();
  std::vector<int> choices;
  for (int q = 0; q < kNumCompareQuantities; ++q)
    if (truth || !kCompareQuantities[q].truth) choices.push_back(q);
  if (std::find(choices.begin(), choices.end(), state.compare_quantity) == choices.end())
    state.compare_quantity = choices.front();
  const CompareQuantity& q = kCompareQuantities[state.compare_quantity];
  ImGui::SetNextItemWidth(220);
  if (ImGui::BeginCombo("quantity", q.title)) {
    for (const int c : choices)
      if (ImGui::Selectable(kCompareQuantities[c].title, c == state.compare_quantity))
        state.compare_quantity = c;
    ImGui::EndCombo();
  }
  static SessionOverview::Data diff;
  CompareDifference(a, b, q.series, diff);
  const ImGuiTableFlags flags =
      ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingStretchProp;
  if (ImGui::BeginTable("compare", 5, flags, ImVec2(avail, 0))) {
    ImGui::TableSetupColumn("set");
    ImGui::TableSetupColumn("mean A");
    ImGui::TableSetupColumn("mean B");
    ImGui::TableSetupColumn("B - A");
    ImGui::TableSetupColumn("largest |B - A|");
    ImGui::TableHeadersRow();
    for (std::size_t i = 0; i < p.sets().size(); ++i) {
      const auto [ma, mb] = CompareMeans(a, b, i, q.series);
      const Rgb& c = p.sets()[i].colour;
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextColored(ImVec4(c.r / 255.f, c.g / 255.f, c.b / 255.f, 1.f), "%s",
                         p.sets()[i].name.c_str());
      ImGui::TableNextColumn();
      ImGui::Text("%.3g %s", ma, q.unit);
      ImGui::TableNextColumn();
      ImGui::Text("%.3g %s", mb, q.unit);
      ImGui::TableNextColumn();
      ImGui::Text("%+.3g %s", mb - ma, q.unit);
      ImGui::TableNextColumn();
      ImGui::Text("%.3g %s", LargestDifference(diff, i, q.series), q.unit);
    }
    ImGui::EndTable();
  }
  const Series series = Member(q.series);
  std::vector<PlotSpec> plots = {{"##ca", std::string("A: ") + q.title, q.unit, series},
                                 {"##cb", std::string("B: ") + q.title, q.unit, series},
                                 {"##cd", std::string("B - A: ") + q.title, q.unit, series}};
  plots[1].data = &b;
  plots[2].data = &diff;
  plots[2].line = 0.0;
  DrawPlots(runner, state, plots, 3, avail, 150);
}

// Every event of every set in time order, filtered by text; a click seeks to it.
void DrawEventList(Runner& runner, GuiState& state, float avail) {
  const SessionPlayer& p = runner.player();
  state.event_filter.Draw("filter (kind, set, link, words; -word excludes)", avail * 0.5f);
  ImGui::SameLine();
  ImGui::Checkbox("contacts", &state.timeline_contacts);
  struct Row {
    const TrackerEvent* e;
    std::size_t set;
  };
  std::vector<Row> rows;
  for (std::size_t i = 0; i < state.overview.sets.size(); ++i)
    for (const TrackerEvent& e : state.overview.sets[i].events)
      if (state.timeline_contacts || !IsContact(e)) rows.push_back({&e, i});
  std::stable_sort(rows.begin(), rows.end(),
                   [](const Row& a, const Row& b) { return a.e->t < b.e->t; });
  const double now = runner.session().t(std::max(0, runner.sample()));
  ImGui::BeginChild("events", ImVec2(avail, 0), true);
  int shown = 0;
  bool scrolled = state.event_list_t == now;  // the list follows the current time
  for (const Row& r : rows) {
    char line[400];
    std::snprintf(line, sizeof line, "%8.3f s  %-4s  %-17s %s", r.e->t,
                  p.sets()[r.set].name.c_str(), EventKindName(r.e->kind),
                  EventMessage(*r.e, p.models().hand).c_str());
    if (!state.event_filter.PassFilter(line)) continue;
    ImGui::PushID(shown++);
    const ImU32 c = Im(EventColour(*r.e));
    ImGui::PushStyleColor(ImGuiCol_Text, ImGui::ColorConvertU32ToFloat4(c));
    if (ImGui::Selectable(line, std::abs(r.e->t - now) < 1e-6))
      state.actions.push_back({ActionKind::kSeek, runner.SampleAt(r.e->t)});
    if (!scrolled && r.e->t >= now - 1e-6) ImGui::SetScrollHereY(0.3f), scrolled = true;
    ImGui::PopStyleColor();
    ImGui::PopID();
  }
  state.event_list_t = now;
  if (shown == 0)
    ImGui::TextUnformatted(state.overview.progress.done ? "no events" : "finding events...");
  ImGui::EndChild();
}

// Keys of the views (not while typing): space plays or pauses, [ and ] jump to the previous and
// next event.
void HandleKeys(Runner& runner, GuiState& state) {
  const ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput) return;
  const Session& s = runner.session();
  const double now = s.t(std::max(0, runner.sample()));
  const std::size_t sets = runner.player().sets().size();
  state.hidden.resize(sets, 0);
  for (const ImWchar c : io.InputQueueCharacters) {
    if (c == ' ') state.actions.push_back({ActionKind::kTogglePlay});
    if (c == '[' || c == ']')
      if (const TrackerEvent* e = NextEvent(state, now, c == '[' ? -1 : 1))
        state.actions.push_back({ActionKind::kSeek, runner.SampleAt(e->t)});
    if (c >= '1' && c <= '9' && static_cast<std::size_t>(c - '1') < sets)
      state.hidden[static_cast<std::size_t>(c - '1')] ^= 1;
    if (c == 'h' || c == '?') state.help = !state.help;
  }
  // Arrows: a sample back or on; with shift, a camera frame.
  const bool left = ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_LeftArrow));
  const bool right = ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_RightArrow));
  if (!left && !right) return;
  if (!io.KeyShift) {
    state.actions.push_back({ActionKind::kSeek, runner.sample() + (right ? 1 : -1)});
    return;
  }
  if (right) {
    state.actions.push_back({ActionKind::kStepFrame});
    return;
  }
  // The frame before the last one shown (or the first, when none is before it).
  const auto& frames = s.camera_frames();
  int f = runner.frame();
  while (f >= 0 && frames[static_cast<std::size_t>(f)].t > now + kTimeTolerance) --f;
  if (f >= 1) state.actions.push_back({ActionKind::kSeek, runner.SampleAt(frames[f - 1].t)});
}

// The keys, over the views (h).
void DrawHelp(GuiState& state, int width, int height) {
  if (!state.help) return;
  ImGui::SetNextWindowPos(
      ImVec2(static_cast<float>(width) * 0.5f, static_cast<float>(height) * 0.4f), ImGuiCond_Always,
      ImVec2(0.5f, 0.5f));
  ImGui::Begin("keys", &state.help,
               ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoSavedSettings);
  const char* rows[][2] = {{"space", "play / pause"},
                           {"left / right", "one joint sample back / on"},
                           {"shift + left / right", "one camera frame back / on"},
                           {"[ / ]", "previous / next event (contacts as the Events tab says)"},
                           {"1 ... 9", "show / hide set 1 ... 9 in the timeline and the plots"},
                           {"wheel, right drag", "zoom, pan the time window (timeline, plots)"},
                           {"double click", "the whole session again"},
                           {"click, drag", "seek (timeline, plots, event list)"},
                           {"h or ?", "this help"}};
  for (const auto& row : rows) {
    ImGui::TextColored(ImVec4(0.6f, 0.8f, 1.0f, 1.0f), "%-22s", row[0]);
    ImGui::SameLine();
    ImGui::TextUnformatted(row[1]);
  }
  ImGui::End();
}

// Where the camera panel draws a point of the palm frame at the current camera frame.
bool CameraPixel(Runner& runner, const Vec3& X_P, Vec2& pixel) {
  const Session& s = runner.session();
  if (!s.info().camera || runner.frame() < 0) return false;
  const Vec3 X_C =
      s.camera_frames().at(static_cast<std::size_t>(runner.frame())).T_PC.inverse() * X_P;
  if (X_C.z() <= 1e-6) return false;
  pixel = s.info().camera->Project(X_C);
  return true;
}

// Where the picture draws a point of the palm frame, in the picture's pixels: in the camera panel
// (panel 0: drawn 1:1 from the left) or in the external 3-D view (panel 1).
bool PicturePixel(Runner& runner, int panel, const Vec3& X_P, Vec2& pixel) {
  if (panel == 0) return CameraPixel(runner, X_P, pixel);
  const FrameComposer::ExternalView& v = runner.external_view();
  if (!v.valid) return false;
  const Vec3 X_C = v.T_PC.inverse() * X_P;
  if (X_C.z() <= 1e-6) return false;
  pixel = Vec2(v.x0, v.y0) + v.scale * v.K.Project(X_C);
  return true;
}

// The selection in words, "SET/LINK" or "SET/visual:ID" ("nothing"), and where the camera panel
// (`pixel`) and the 3-D view (`pixel_3d`) draw it, in the picture's pixels (a link: its nearest
// contact's point on the object; NaN when not drawn).
std::string DescribeSelection(Runner& runner, const GuiState& state, Vec2& pixel, Vec2& pixel_3d) {
  const SessionPlayer& p = runner.player();
  const std::size_t set = InspectedSet(runner, state);
  pixel = pixel_3d = Vec2::Constant(NAN);
  const std::string prefix = p.sets()[set].name + "/";
  if (state.inspect_visual >= 0) {
    for (const FilterTrace::Visual& v : runner.visual(set))
      if (v.id == state.inspect_visual) pixel = v.measured;
    return prefix + "visual:" + std::to_string(state.inspect_visual);
  }
  const auto& links = p.models().hand.links;
  if (state.inspect_link < 0 || static_cast<std::size_t>(state.inspect_link) >= links.size())
    return "nothing";
  for (int panel = 0; panel < 2; ++panel) {
    double nearest = INFINITY;
    for (const FilterTrace::Contact& c : p.tracker(set).filter().trace().contacts) {
      Vec2 q;
      if (c.link == state.inspect_link && c.distance < nearest &&
          PicturePixel(runner, panel, c.c_o_P, q))
        nearest = c.distance, (panel == 0 ? pixel : pixel_3d) = q;
    }
  }
  return prefix + links[static_cast<std::size_t>(state.inspect_link)].name;
}

// A click on the picture (its pixel `at`) selects the contact or visual measurement drawn nearest
// to it within 12 px, in the camera panel or the 3-D view: the inspected set's, else any set's.
// The Inspector tab comes to the front.
void SelectInPicture(Runner& runner, GuiState& state, const Vec2& at) {
  const SessionPlayer& p = runner.player();
  double best = 12.0;
  int set = -1, link = -1, visual = -1;
  // The inspected set's first: the sets' markers of one contact lie within a pixel or two.
  const std::size_t inspected = InspectedSet(runner, state);
  for (std::size_t n = 0; n <= p.sets().size() && set < 0; ++n) {
    const std::size_t i = n == 0 ? inspected : n - 1;
    if (state.Hidden(i) || (n > 0 && i == inspected)) continue;
    for (const FilterTrace::Contact& c : p.tracker(i).filter().trace().contacts)
      for (int panel = 0; panel < 2; ++panel) {
        Vec2 q;
        if (!PicturePixel(runner, panel, c.c_o_P, q)) continue;
        const double d = (q - at).norm();
        if (d < best) best = d, set = static_cast<int>(i), link = c.link, visual = -1;
      }
    for (const FilterTrace::Visual& v : runner.visual(i)) {
      if (!runner.session().info().camera) break;
      const double d = (v.measured - at).norm();
      if (d < best) best = d, set = static_cast<int>(i), link = -1, visual = v.id;
    }
  }
  if (set < 0) return;
  state.inspect_set = set, state.inspect_link = link, state.inspect_visual = visual;
  state.open_inspector = state.pictures_dirty = true;
}

// gui --script FILE: one command per line (# starts a comment), each run at a frame of its own;
// inputs take effect by the next command:
//   wait N                      N frames
//   wait-events                 until the event overview has the whole session
//   seek T                      to session time T [s]
//   key C                       type character C (`space` for a space)
//   click X Y                   move to window pixel (X, Y), press the left button, release it
//   scroll X Y N                move to (X, Y), turn the wheel N notches (positive: zoom in)
//   drag X1 Y1 X2 Y2            press at (X1, Y1), move to (X2, Y2) holding it, release
//   expect panel W TOL          the left panel is W px wide within TOL (its splitter)
//   expect picture S TOL        the picture takes S of the views' width within TOL
//   press KEY                   left, right, shift+left or shift+right
//   screenshot FILE             save this frame as PNG
//   expect time T TOL           the current time is T within TOL [s]
//   expect events KIND MIN      at least MIN events of KIND (`any`: of every kind), all sets
//   expect window A B TOL       the timeline and plots show [A, B] s within TOL
//   click-picture U V           click the composed picture's pixel (U, V) (click-camera: the
//                               same; the camera panel is drawn 1:1 from the picture's left)
//   select SET LINK             the inspector inspects SET and selects LINK
//   expect selected WHAT        SET/LINK, SET/visual:ID or nothing; says where it is drawn
//   expect contact STATUS       the selected link's status now, in the table and the history
//   param NAME VALUE            a parameter of the panel (params.json's name, a.b when nested)
//   compare [FILE]              A/B with the panel's parameters, or FILE's
//   wait-compare                until B is replayed
//   expect difference SET QUANTITY MIN MAX   the largest |B - A| of a series lies in [MIN, MAX]
class GuiScript {
 public:
  static GuiScript Load(const std::string& path) {
    GuiScript script;
    script.path_ = path;
    std::ifstream in(path);
    if (!in) throw InputError(path + ": cannot read the GUI script");
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
      std::istringstream words(line);
      Command c;
      c.line = number;
      if (!(words >> c.verb)) continue;
      const auto fail = [&](const char* expected) {
        throw InputError(path + ":" + std::to_string(number) + ": '" + line + "': expected " +
                         expected);
      };
      if (c.verb == "wait") {
        if (!(words >> c.a) || c.a < 1) fail("wait N (frames, >= 1)");
      } else if (c.verb == "wait-events") {
      } else if (c.verb == "seek") {
        if (!(words >> c.a)) fail("seek T (seconds)");
      } else if (c.verb == "key") {
        if (!(words >> c.text) || (c.text.size() != 1 && c.text != "space"))
          fail("key C (one character, or space)");
      } else if (c.verb == "click") {
        if (!(words >> c.a >> c.b)) fail("click X Y (window pixels)");
      } else if (c.verb == "scroll") {
        if (!(words >> c.a >> c.b >> c.c)) fail("scroll X Y N (window pixels, notches)");
      } else if (c.verb == "drag") {
        if (!(words >> c.a >> c.b >> c.c >> c.d)) fail("drag X1 Y1 X2 Y2 (window pixels)");
      } else if (c.verb == "press") {
        if (!(words >> c.text) || (c.text != "left" && c.text != "right" &&
                                   c.text != "shift+left" && c.text != "shift+right"))
          fail("press left, right, shift+left or shift+right");
      } else if (c.verb == "screenshot") {
        if (!(words >> c.text)) fail("screenshot FILE");
      } else if (c.verb == "click-camera" || c.verb == "click-picture") {
        if (!(words >> c.a >> c.b)) fail((c.verb + " U V (the picture's pixels)").c_str());
      } else if (c.verb == "select") {
        if (!(words >> c.text >> c.text2)) fail("select SET LINK (names)");
      } else if (c.verb == "param") {
        if (!(words >> c.text >> c.text2)) fail("param NAME VALUE (params.json's names)");
      } else if (c.verb == "compare") {
        words >> c.text;  // optional: B's parameter file
      } else if (c.verb == "wait-compare") {
      } else if (c.verb == "expect") {
        std::string what;
        words >> what;
        if (what == "time") {
          c.verb = "expect-time";
          if (!(words >> c.a >> c.b)) fail("expect time T TOL");
        } else if (what == "window") {
          c.verb = "expect-window";
          if (!(words >> c.a >> c.b >> c.c)) fail("expect window A B TOL");
        } else if (what == "panel") {
          c.verb = "expect-panel";
          if (!(words >> c.a >> c.b)) fail("expect panel WIDTH TOL (pixels)");
        } else if (what == "picture") {
          c.verb = "expect-picture";
          if (!(words >> c.a >> c.b)) fail("expect picture SHARE TOL");
        } else if (what == "selected") {
          c.verb = "expect-selected";
          if (!(words >> c.text)) fail("expect selected SET/LINK, SET/visual:ID or nothing");
        } else if (what == "contact") {
          c.verb = "expect-contact";
          bool known = false;
          if (words >> c.text) {
            known = c.text == "fused";
            for (int k = 0; k <= static_cast<int>(ContactStatus::kGated); ++k)
              known = known || c.text == ContactStatusName(static_cast<ContactStatus>(k));
          }
          if (!known)
            fail(
                "expect contact STATUS (none, candidate, rejected, kinematic, torque, gated, or "
                "fused: kinematic or torque)");
        } else if (what == "difference") {
          c.verb = "expect-difference";
          bool known = false;
          if (words >> c.text >> c.text2 >> c.a >> c.b)
            for (const CompareQuantity& q : kCompareQuantities) known = known || c.text2 == q.name;
          if (!known)
            fail(
                "expect difference SET QUANTITY MIN MAX (position_error, orientation_error, "
                "sigma_position, sigma_orientation, nees or penetration)");
        } else if (what == "events") {
          c.verb = "expect-events";
          if (!(words >> c.text >> c.a)) fail("expect events KIND MIN");
          bool known = c.text == "any";
          for (int k = 0; k < kNumEventKinds; ++k)
            known = known || c.text == EventKindName(static_cast<EventKind>(k));
          if (!known) fail("an event kind of FORMAT.md, or any");
        } else {
          fail("expect time, window, panel, picture, selected, contact, difference or events ...");
        }
      } else {
        fail(
            "wait, wait-events, seek, key, press, click, click-camera, click-picture, scroll, "
            "drag, "
            "select, "
            "param, compare, wait-compare, screenshot or expect");
      }
      script.commands_.push_back(c);
    }
    return script;
  }

  bool done() const {
    return next_ >= commands_.size() && wait_ <= 0 && !pressing_ && !releasing_ && wheel_ == 0.0f &&
           key_ < 0 && drag_.empty();
  }
  int failures() const { return failures_; }

  // Before ImGui::NewFrame: this frame's inputs and checks.
  void BeforeFrame(Runner& runner, GuiState& state, ImGuiIO& io) {
    io.MousePos = mouse_;
    io.KeyShift = shift_;
    if (key_ >= 0) {  // the frame after the press
      io.KeysDown[key_] = false;
      key_ = -1;
      io.KeyShift = shift_ = false;
      return;
    }
    if (wheel_ != 0.0f) {  // the frame after the move
      io.MouseWheel = std::exchange(wheel_, 0.0f);
      return;
    }
    if (!drag_.empty()) {  // pressed where the drag starts, then one position a frame
      io.MouseDown[0] = drag_.size() > 1;
      mouse_ = io.MousePos = drag_.front();
      drag_.pop_front();
      return;
    }
    if (pressing_) {  // the frame after the move: ImGui knows what is under the mouse
      io.MouseDown[0] = true;
      pressing_ = false;
      releasing_ = true;
      return;
    }
    if (releasing_) {  // the frame after the press
      io.MouseDown[0] = false;
      releasing_ = false;
      return;
    }
    if (wait_ > 0) {
      --wait_;
      return;
    }
    while (next_ < commands_.size()) {
      const Command& c = commands_[next_++];
      const std::string where = path_ + ":" + std::to_string(c.line) + ": ";
      if (c.verb == "screenshot") {
        screenshot_ = c.text;
        continue;
      }
      if (c.verb == "select") {
        const SessionPlayer& p = runner.player();
        int set = -1, link = -1;
        for (std::size_t i = 0; i < p.sets().size(); ++i)
          if (p.sets()[i].name == c.text) set = static_cast<int>(i);
        for (std::size_t l = 0; l < p.models().hand.links.size(); ++l)
          if (p.models().hand.links[l].name == c.text2) link = static_cast<int>(l);
        if (set < 0 || link < 0) {
          Report(where, false, "no set '" + c.text + "' or no link '" + c.text2 + "'");
          continue;
        }
        state.inspect_set = set, state.inspect_link = link, state.inspect_visual = -1;
        state.open_inspector = state.pictures_dirty = true;
        return;
      }
      if (c.verb == "param") {
        // Through params.json's own reader: a name it lacks or a value out of range fails here.
        try {
          nlohmann::json j = nlohmann::json::parse(TrackerParamsToJson(state.params));
          nlohmann::json* at = &j;
          std::istringstream path(c.text);
          for (std::string key; std::getline(path, key, '.');) {
            if (!at->is_object() || !at->contains(key))
              throw InputError("no parameter '" + c.text + "'");
            at = &(*at)[key];
          }
          if (at->is_boolean())
            *at = c.text2 == "true";
          else if (at->is_number_integer())
            *at = std::stol(c.text2);
          else
            *at = std::stod(c.text2);
          state.params = TrackerParamsFromJson(j.dump(), where + "param");
          Report(where, true, c.text + " = " + c.text2);
        } catch (const std::exception& e) {
          Report(where, false, e.what());
        }
        continue;
      }
      if (c.verb == "compare") {
        if (!c.text.empty())
          std::snprintf(state.params_path, sizeof state.params_path, "%s", c.text.c_str());
        state.actions.push_back({ActionKind::kCompare, c.text.empty() ? 0 : 1});
        return;
      }
      if (c.verb == "wait-compare") {
        if (runner.compare()) runner.compare()->Wait();
        ReadOverview(runner, state);
        continue;
      }
      if (c.verb == "expect-difference") {
        runner.overview().Wait();
        if (runner.compare()) runner.compare()->Wait();
        ReadOverview(runner, state);
        const SessionPlayer& p = runner.player();
        std::size_t set = p.sets().size();
        for (std::size_t i = 0; i < p.sets().size(); ++i)
          if (p.sets()[i].name == c.text) set = i;
        const CompareQuantity* q = nullptr;
        for (const CompareQuantity& candidate : kCompareQuantities)
          if (c.text2 == candidate.name) q = &candidate;
        if (!runner.compare() || set == p.sets().size() || !q) {
          Report(where, false, runner.compare() ? "no set " + c.text : "no comparison running");
          continue;
        }
        SessionOverview::Data diff;
        CompareDifference(state.overview, state.compare, q->series, diff);
        const double d = LargestDifference(diff, set, q->series);
        Report(where, d >= c.a && d <= c.b && diff.t.size() == state.overview.t.size(),
               "largest |B - A| of " + c.text + " " + c.text2 + " " + FormatDouble(d) + " over " +
                   std::to_string(diff.t.size()) + " samples, expected in [" + FormatDouble(c.a) +
                   ", " + FormatDouble(c.b) + "]");
        continue;
      }
      if (c.verb == "expect-selected") {
        Vec2 pixel, pixel_3d;
        const std::string selected = DescribeSelection(runner, state, pixel, pixel_3d);
        char drawn[160] = "";
        if (std::isfinite(pixel.x()))
          std::snprintf(drawn, sizeof drawn, " (drawn at %.2f %.2f px)", pixel.x(), pixel.y());
        if (std::isfinite(pixel_3d.x()))
          std::snprintf(drawn + std::strlen(drawn), sizeof drawn - std::strlen(drawn),
                        " (3-D view at %.2f %.2f px)", pixel_3d.x(), pixel_3d.y());
        // A tag corner's history (DrawVisualHistory): the images that measured it, per set.
        std::string history = VisualHistoryCounts(runner, state);
        if (!history.empty()) history = " (history: " + history + ")";
        Report(where, selected == c.text,
               "selected " + selected + drawn + history + ", expected " + c.text);
        continue;
      }
      if (c.verb == "wait-events" || c.verb == "expect-events" || c.verb == "expect-contact") {
        runner.overview().Wait();
        ReadOverview(runner, state);
      }
      if (c.verb == "expect-time") {
        const double t = runner.session().t(std::max(0, runner.sample()));
        Report(where, std::abs(t - c.a) <= c.b,
               "time " + FormatDouble(t) + " s, expected " + FormatDouble(c.a) + " +- " +
                   FormatDouble(c.b));
        continue;
      }
      if (c.verb == "expect-window") {
        const auto [a, b] = TimeWindow(runner.session(), state);
        Report(where, std::abs(a - c.a) <= c.c && std::abs(b - c.b) <= c.c,
               "window [" + FormatDouble(a) + ", " + FormatDouble(b) + "] s, expected [" +
                   FormatDouble(c.a) + ", " + FormatDouble(c.b) + "] +- " + FormatDouble(c.c));
        continue;
      }
      if (c.verb == "expect-panel") {
        Report(where, std::abs(state.panel_width - c.a) <= c.b,
               "panel " + FormatDouble(state.panel_width) + " px wide, expected " +
                   FormatDouble(c.a) + " +- " + FormatDouble(c.b));
        continue;
      }
      if (c.verb == "expect-picture") {
        Report(where, std::abs(state.picture_share - c.a) <= c.b,
               "picture " + FormatDouble(state.picture_share) + " of the views' width, expected " +
                   FormatDouble(c.a) + " +- " + FormatDouble(c.b));
        continue;
      }
      if (c.verb == "expect-events") {
        long count = 0;
        for (const auto& set : state.overview.sets)
          for (const TrackerEvent& e : set.events)
            count += c.text == "any" || c.text == EventKindName(e.kind);
        Report(where, count >= c.a,
               std::to_string(count) + " events of " + c.text + ", expected at least " +
                   FormatDouble(c.a));
        continue;
      }
      if (c.verb == "expect-contact") {
        // What the inspector's table says (the GUI's player, at the current sample) and what its
        // history says there (the overview's replay): two runs, one answer.
        const std::size_t set = InspectedSet(runner, state);
        const std::size_t link = static_cast<std::size_t>(std::max(0, state.inspect_link));
        std::vector<LinkContact> links;
        LinkContacts(runner.player().tracker(set).filter().trace(),
                     runner.player().models().hand.links.size(), links);
        const std::string now =
            link < links.size() ? ContactStatusName(links[link].status) : "nothing";
        std::string history = "nothing";
        const auto k = static_cast<std::size_t>(std::max(0, runner.sample()));
        if (set < state.overview.sets.size() &&
            link < state.overview.sets[set].link_status.size() &&
            k < state.overview.sets[set].link_status[link].size())
          history = ContactStatusName(
              static_cast<ContactStatus>(state.overview.sets[set].link_status[link][k]));
        const auto matches = [&](const std::string& status) {
          return status == c.text ||
                 (c.text == "fused" && (status == "kinematic" || status == "torque"));
        };
        Report(where, state.inspect_link >= 0 && matches(now) && matches(history),
               "contact " + now + " (table), " + history + " (history), expected " + c.text);
        continue;
      }
      if (c.verb == "wait-events") continue;
      if (c.verb == "wait") {
        wait_ = static_cast<int>(c.a) - 1;
      } else if (c.verb == "seek") {
        state.actions.push_back({ActionKind::kSeek, runner.SampleAt(c.a)});
      } else if (c.verb == "key") {
        io.AddInputCharacter(c.text == "space" ? ' ' : static_cast<unsigned>(c.text[0]));
      } else if (c.verb == "click") {
        mouse_ = ImVec2(static_cast<float>(c.a), static_cast<float>(c.b));
        io.MousePos = mouse_;
        pressing_ = true;
      } else if (c.verb == "click-camera" || c.verb == "click-picture") {
        const float scale = state.picture_max.x > state.picture_min.x && state.picture_width > 0
                                ? (state.picture_max.x - state.picture_min.x) / state.picture_width
                                : 0.0f;
        mouse_ = ImVec2(state.picture_min.x + static_cast<float>(c.a) * scale,
                        state.picture_min.y + static_cast<float>(c.b) * scale);
        io.MousePos = mouse_;
        pressing_ = true;
      } else if (c.verb == "press") {
        shift_ = c.text.rfind("shift+", 0) == 0;
        key_ = io.KeyMap[c.text.find("left") != std::string::npos ? ImGuiKey_LeftArrow
                                                                  : ImGuiKey_RightArrow];
        io.KeyShift = shift_;
        if (key_ >= 0) io.KeysDown[key_] = true;
      } else if (c.verb == "scroll") {
        mouse_ = ImVec2(static_cast<float>(c.a), static_cast<float>(c.b));
        io.MousePos = mouse_;
        wheel_ = static_cast<float>(c.c);
      } else if (c.verb == "drag") {
        // This frame the mouse moves to the start; the next it presses there, then it moves in
        // eight steps to the end, holding the button, and releases it the frame after.
        mouse_ = ImVec2(static_cast<float>(c.a), static_cast<float>(c.b));
        io.MousePos = mouse_;
        drag_.push_back(mouse_);
        for (int i = 1; i <= 8; ++i)
          drag_.push_back(ImVec2(static_cast<float>(c.a + (c.c - c.a) * i / 8.0),
                                 static_cast<float>(c.b + (c.d - c.b) * i / 8.0)));
        drag_.push_back(drag_.back());  // released at the end
      }
      return;  // one input per frame
    }
  }
  // After the frame is drawn: where to save it ("" : nowhere).
  std::string TakeScreenshot() { return std::exchange(screenshot_, std::string()); }

 private:
  struct Command {
    int line = 0;
    std::string verb, text, text2;
    double a = 0.0, b = 0.0, c = 0.0, d = 0.0;
  };
  void Report(const std::string& where, bool ok, const std::string& what) {
    std::cout << where << (ok ? "ok: " : "FAILED: ") << what << "\n";
    failures_ += !ok;
  }
  std::string path_;
  std::vector<Command> commands_;
  std::size_t next_ = 0;
  int wait_ = 0;
  bool pressing_ = false, releasing_ = false;
  float wheel_ = 0.0f;
  std::deque<ImVec2> drag_;  // the positions a drag still goes through, one a frame
  int key_ = -1;             // io.KeysDown index held for a frame
  bool shift_ = false;
  ImVec2 mouse_{-1.0f, -1.0f};
  std::string screenshot_;
  int failures_ = 0;
};

// The right: the composed picture (orbit and zoom of its 3-D view by mouse) above the tabs.
void DrawViews(Runner& runner, GuiState& state, const Textures& tex, int width, int height) {
  const SessionPlayer& p = runner.player();
  ImGui::SetNextWindowPos(ImVec2(state.panel_width, 0));
  ImGui::SetNextWindowSize(
      ImVec2(static_cast<float>(width) - state.panel_width, static_cast<float>(height)));
  ImGui::Begin("views", nullptr,
               ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoTitleBar);
  const float avail = ImGui::GetContentRegionAvail().x;
  const Session& shown = runner.player().session();
  ImGui::TextUnformatted(!shown.info().camera ? "3-D view (the session has no camera)"
                         : shown.has_groundtruth()
                             ? "camera + estimates (truth dashed); on its right the virtual view "
                               "and the 3-D view"
                             : "camera + estimates (no ground truth); on its right the virtual "
                               "view and the 3-D view");
  tex.picture.Show(avail * state.picture_share);
  const bool picture_hovered = ImGui::IsItemHovered();
  const ImVec2 picture_min = ImGui::GetItemRectMin(), picture_max = ImGui::GetItemRectMax();
  state.picture_min = picture_min, state.picture_max = picture_max;
  state.picture_width = tex.picture.width;
  // The splitter under the picture: dragged, the picture grows or shrinks (aspect kept), the
  // timeline and tabs below take the rest.
  ImGui::InvisibleButton("##picture split", ImVec2(avail, 6.0f));
  if (ImGui::IsItemHovered() || ImGui::IsItemActive())
    ImGui::SetMouseCursor(ImGuiMouseCursor_ResizeNS);
  if (ImGui::IsItemActive() && ImGui::GetIO().MouseDelta.y != 0.0f && tex.picture.height > 0) {
    const float aspect =
        static_cast<float>(tex.picture.width) / static_cast<float>(tex.picture.height);
    state.picture_share = std::clamp(
        state.picture_share + ImGui::GetIO().MouseDelta.y * aspect / avail, kMinPictureShare, 1.0f);
    state.layout_changed = true;
  }
  const ImGuiIO& mouse = ImGui::GetIO();
  if (picture_hovered && ImGui::IsMouseReleased(ImGuiMouseButton_Left) &&
      mouse.MouseDragMaxDistanceSqr[0] < mouse.MouseDragThreshold * mouse.MouseDragThreshold &&
      tex.picture.width > 0) {
    const ImGuiIO& io = mouse;
    const double scale = tex.picture.width / static_cast<double>(picture_max.x - picture_min.x);
    SelectInPicture(
        runner, state,
        Vec2((io.MousePos.x - picture_min.x) * scale, (io.MousePos.y - picture_min.y) * scale));
  }
  if (picture_hovered) {
    const ImGuiIO& io = ImGui::GetIO();
    // Over the 3-D view: where the composer last drew it, in the picture's pixels.
    const FrameComposer::ExternalView& v = runner.external_view();
    const double scale = tex.picture.width / static_cast<double>(picture_max.x - picture_min.x);
    const double u = (io.MousePos.x - picture_min.x) * scale,
                 w = (io.MousePos.y - picture_min.y) * scale;
    const bool over_3d =
        v.valid && u >= v.x0 && u < v.x0 + v.width && w >= v.y0 && w < v.y0 + v.height;
    if (over_3d && ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
      state.orbit.azimuth -= 0.01 * io.MouseDelta.x;
      state.orbit.elevation = std::clamp(state.orbit.elevation + 0.01 * io.MouseDelta.y, -1.5, 1.5);
      state.pictures_dirty = true;
    }
    if (over_3d && io.MouseWheel != 0.0f) {
      state.orbit.distance =
          std::clamp(state.orbit.distance * (1.0 - 0.1 * io.MouseWheel), 0.1, 2.0);
      state.pictures_dirty = true;
    }
  }
  DrawTimeline(runner, state, avail);
  if (ImGui::BeginTabBar("tabs")) {
    if (ImGui::BeginTabItem("Errors and uncertainty")) {
      DrawErrorPlots(runner, state, avail);
      ImGui::EndTabItem();
    }
    if (ImGui::BeginTabItem("Biases and counts")) {
      DrawBiases(p, avail);
      DrawCountPlots(runner, state, avail);
      ImGui::EndTabItem();
    }
    if (ImGui::BeginTabItem("Feature matching")) {
      DrawFeatureMatching(p, tex, avail);
      ImGui::EndTabItem();
    }
    if (ImGui::BeginTabItem("Events")) {
      DrawEventList(runner, state, avail);
      ImGui::EndTabItem();
    }
    if (ImGui::BeginTabItem("Inspector", nullptr,
                            std::exchange(state.open_inspector, false)
                                ? ImGuiTabItemFlags_SetSelected
                                : ImGuiTabItemFlags_None)) {
      DrawInspector(runner, state, tex, avail);
      ImGui::EndTabItem();
    }
    if (ImGui::BeginTabItem("Compare", nullptr,
                            std::exchange(state.open_compare, false) ? ImGuiTabItemFlags_SetSelected
                                                                     : ImGuiTabItemFlags_None)) {
      DrawCompare(runner, state, avail);
      ImGui::EndTabItem();
    }
    ImGui::EndTabBar();
  }
  ImGui::End();
}

void DrawUi(Runner& runner, GuiState& state, const Textures& tex, int width, int height) {
  ReadOverview(runner, state);
  HandleKeys(runner, state);
  DrawControlPanel(runner, state, height);
  DrawViews(runner, state, tex, width, height);
  DrawPanelSplitter(state, width, height);
  DrawHelp(state, width, height);
}

// What the held-to figures need, logged at the end of a run: the time a seek takes (from the
// action to the picture uploaded) and how fast playback goes against the session's clock.
class Timings {
 public:
  // Around one frame's actions and picture update.
  void Begin(const GuiState& state, double session_t) {
    seek_ = std::any_of(state.actions.begin(), state.actions.end(),
                        [](const Action& a) { return a.kind == ActionKind::kSeek; });
    playing_ = state.playing;
    t0_ = session_t;
    start_ = std::chrono::steady_clock::now();
  }
  void End(double session_t) {
    const auto now = std::chrono::steady_clock::now();
    if (seek_) seek_ms_.push_back(std::chrono::duration<double, std::milli>(now - start_).count());
    if (playing_ && was_playing_) {
      played_session_ += session_t - t0_;
      played_wall_ += std::chrono::duration<double>(now - last_end_).count();
    }
    was_playing_ = playing_;
    last_end_ = now;
  }
  // ", seeks N (median A ms, slowest B ms), playback R x real time"; empty when neither.
  std::string Report() const {
    std::ostringstream out;
    out << std::fixed << std::setprecision(1);
    if (!seek_ms_.empty()) {
      std::vector<double> v = seek_ms_;
      std::sort(v.begin(), v.end());
      out << ", seeks " << v.size() << " (median " << v[v.size() / 2] << " ms, slowest " << v.back()
          << " ms)";
    }
    if (played_wall_ > 0.0)
      out << ", playback " << std::setprecision(2) << played_session_ / played_wall_
          << "x real time";
    return out.str();
  }

 private:
  bool seek_ = false, playing_ = false, was_playing_ = false;
  double t0_ = 0.0, played_session_ = 0.0, played_wall_ = 0.0;
  std::chrono::steady_clock::time_point start_, last_end_;
  std::vector<double> seek_ms_;
};

int RunHeadless(const GuiCommand& cmd, RenderThread& render, Runner& runner, GuiState& state,
                GuiScript* script) {
  // OSMesa through the renderer's loader (osmesa.hpp): the process loads it only here.
  const auto create_context = reinterpret_cast<decltype(&::OSMesaCreateContextExt)>(
      OsMesaFunction("OSMesaCreateContextExt"));
  const auto make_current =
      reinterpret_cast<decltype(&::OSMesaMakeCurrent)>(OsMesaFunction("OSMesaMakeCurrent"));
  const auto destroy_context =
      reinterpret_cast<decltype(&::OSMesaDestroyContext)>(OsMesaFunction("OSMesaDestroyContext"));
  OSMesaContext ctx = create_context(OSMESA_RGBA, 24, 0, 0, nullptr);
  if (!ctx) throw std::runtime_error("gui: cannot create an offscreen OpenGL context");
  std::vector<std::uint8_t> buffer(static_cast<std::size_t>(cmd.width) * cmd.height * 4);
  make_current(ctx, buffer.data(), GL_UNSIGNED_BYTE, cmd.width, cmd.height);
  GuiGl gl;
  gl.Load(OsMesaFunction);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsDark();
  const OffscreenImGuiRenderer imgui_gl(OsMesaFunction);
  // The arrows at GLFW's key codes, as the window's backend maps them (gui --script presses them).
  ImGui::GetIO().KeyMap[ImGuiKey_LeftArrow] = GLFW_KEY_LEFT;
  ImGui::GetIO().KeyMap[ImGuiKey_RightArrow] = GLFW_KEY_RIGHT;
  Textures tex;
  const int frames = script ? std::numeric_limits<int>::max() : cmd.frames > 0 ? cmd.frames : 1;
  if (!script) runner.overview().Wait();  // the screenshot shows every event
  // OSMesa's buffer holds the last frame, bottom row first.
  const auto picture = [&] {
    Image8 img(cmd.width, cmd.height, 3);
    for (int y = 0; y < cmd.height; ++y)
      for (int x = 0; x < cmd.width; ++x)
        for (int c = 0; c < 3; ++c)
          img.pixel(x, y)[c] =
              buffer[(static_cast<std::size_t>(cmd.height - 1 - y) * cmd.width + x) * 4 +
                     static_cast<std::size_t>(c)];
    return img;
  };
  int f = 0;
  Timings timings;
  const auto now_t = [&] { return runner.session().t(std::max(0, runner.sample())); };
  for (; f < frames && !(script && script->done()); ++f) {
    timings.Begin(state, now_t());
    render.Run([&] { ApplyActions(runner, state); });
    UpdateTextures(gl, render, runner, state, tex);
    timings.End(now_t());
    ImGuiIO& io = ImGui::GetIO();
    io.DisplaySize = ImVec2(static_cast<float>(cmd.width), static_cast<float>(cmd.height));
    io.DeltaTime = 1.0f / 30.0f;
    if (script) script->BeforeFrame(runner, state, io);
    ImGui::NewFrame();
    DrawUi(runner, state, tex, cmd.width, cmd.height);
    ImGui::Render();
    gl.Viewport(0, 0, cmd.width, cmd.height);
    gl.ClearColor(0.1f, 0.1f, 0.12f, 1.0f);
    gl.Clear(GL_COLOR_BUFFER_BIT);
    imgui_gl.Render(ImGui::GetDrawData());
    gl.Finish();
    if (script)
      if (const std::string file = script->TakeScreenshot(); !file.empty())
        WriteImage(file, picture());
  }
  if (!cmd.screenshot.empty()) WriteImage(cmd.screenshot, picture());
  ImGui::DestroyContext();
  destroy_context(ctx);
  std::cout << "offscreen interface (no display): " << f << " frames, t "
            << runner.session().t(std::max(0, runner.sample())) << " s" << timings.Report();
  if (!cmd.screenshot.empty()) std::cout << ", screenshot " << cmd.screenshot;
  std::cout << "\n";
  return script && script->failures() > 0 ? 1 : 0;
}

}  // namespace

int RunGui(const GuiCommand& cmd) {
  if (cmd.width < 640 || cmd.height < 480)
    throw InputError("gui: the window must be at least 640x480");
  Session session = Session::Load(cmd.session);
  GuiState state;
  LoadGuiLayout(state);
  if (!cmd.params.empty()) state.params = ReadTrackerParams(cmd.params);
  if (!cmd.modalities.empty()) state.sets = ParseModalities(cmd.modalities);
  if (cmd.time >= 0.0) {
    int k = 0;
    while (k + 1 < session.num_samples() && session.t(k + 1) <= cmd.time) ++k;
    state.actions.push_back({ActionKind::kSeek, k});
  }
  state.playing = cmd.play;
  std::unique_ptr<GuiScript> script;
  if (!cmd.script.empty()) script = std::make_unique<GuiScript>(GuiScript::Load(cmd.script));
  const char* display = std::getenv("DISPLAY");
  const bool have_display = display && *display && glfwInit();
  if (!have_display) {
    if (cmd.screenshot.empty() && !script) {
      std::cerr << "inhand: error: no display for the interactive session (set DISPLAY, or use "
                   "--screenshot FILE or --script FILE to render it offscreen)\n";
      return 2;
    }
    RenderThread render;
    std::unique_ptr<Runner> runner;
    render.Run([&] { runner = std::make_unique<Runner>(session, state); });
    const int code = RunHeadless(cmd, render, *runner, state, script.get());
    render.Run([&] { runner.reset(); });
    SaveGuiLayout(state);
    return code;
  }
  state.play_wall_clock = true;
  state.play_last = std::chrono::steady_clock::now();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  GLFWwindow* window = glfwCreateWindow(
      cmd.width, cmd.height, ("inhand: " + session.info().name).c_str(), nullptr, nullptr);
  if (!window) {
    glfwTerminate();
    throw std::runtime_error("gui: cannot open an OpenGL 3.3 window");
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);
  GuiGl gl;
  gl.Load([](const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); });
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 330");
  RenderThread render;
  std::unique_ptr<Runner> runner_owner;
  render.Run([&] { runner_owner = std::make_unique<Runner>(session, state); });
  Runner& runner = *runner_owner;
  Textures tex;
  int frames = 0;
  std::vector<double> frame_ms;
  Timings timings;
  const auto now_t = [&] { return runner.session().t(std::max(0, runner.sample())); };
  auto last = std::chrono::steady_clock::now();
  while (!glfwWindowShouldClose(window) &&
         (script ? !script->done() : cmd.frames < 0 || frames < cmd.frames)) {
    const auto now = std::chrono::steady_clock::now();
    if (frames > 0)
      frame_ms.push_back(std::chrono::duration<double, std::milli>(now - last).count());
    last = now;
    glfwPollEvents();
    timings.Begin(state, now_t());
    render.Run([&] { ApplyActions(runner, state); });
    UpdateTextures(gl, render, runner, state, tex);
    timings.End(now_t());
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    if (script) script->BeforeFrame(runner, state, ImGui::GetIO());
    ImGui::NewFrame();
    int w = 0, h = 0;
    glfwGetFramebufferSize(window, &w, &h);
    DrawUi(runner, state, tex, w, h);
    ImGui::Render();
    gl.Viewport(0, 0, w, h);
    gl.ClearColor(0.1f, 0.1f, 0.12f, 1.0f);
    gl.Clear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    ++frames;
    const bool final_frame = script ? script->done() : cmd.frames > 0 && frames == cmd.frames;
    if (!cmd.screenshot.empty() && final_frame) {
      gl.ReadBuffer(GL_BACK);
      SaveScreenshot(gl, w, h, cmd.screenshot);
    }
    if (script)
      if (const std::string file = script->TakeScreenshot(); !file.empty()) {
        gl.ReadBuffer(GL_BACK);
        SaveScreenshot(gl, w, h, file);
      }
    glfwSwapBuffers(window);
  }
  render.Run([&] { runner_owner.reset(); });
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
  std::sort(frame_ms.begin(), frame_ms.end());
  const double median = frame_ms.empty() ? 0.0 : frame_ms[frame_ms.size() / 2];
  const double p95 =
      frame_ms.empty() ? 0.0 : frame_ms[std::min(frame_ms.size() - 1, frame_ms.size() * 95 / 100)];
  std::cout << "window: " << frames << " frames, frame time median " << median << " ms, p95 " << p95
            << " ms" << timings.Report();
  if (!cmd.screenshot.empty()) std::cout << ", screenshot " << cmd.screenshot;
  std::cout << "\n";
  SaveGuiLayout(state);
  return script && script->failures() > 0 ? 1 : 0;
}

}  // namespace inhand::app
