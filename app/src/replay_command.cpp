#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "inhand/app/commands.hpp"
#include "inhand/app/event_palette.hpp"
#include "inhand/app/frame_composer.hpp"
#include "inhand/app/player.hpp"
#include "inhand/core/error.hpp"
#include "inhand/core/time.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/renderer/timeline_strip.hpp"
#include "inhand/renderer/video.hpp"
#include "inhand/sessions/image_io.hpp"
#include "mcap_export.hpp"
#include "staged_output.hpp"

namespace fs = std::filesystem;

namespace inhand::app {

namespace {

using jsonf::Json;

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
}

struct SetStats {
  std::vector<double> nees;
  std::vector<double> step_us;
  std::vector<double> visual_ms;
  long features_used = 0;
  double sq_pos = 0.0, sq_ori = 0.0;
  int with_truth = 0;
  long constraints = 0;
  double penetration_sum = 0.0, penetration_max = 0.0, penetration_last = 0.0;  // [m]
  double unexplained_sum = 0.0, unexplained_max = 0.0;                          // [N m]
  std::array<double, 4> health_time{};       // [s] per HealthState
  std::map<std::string, double> cause_time;  // [s] per HealthCause, states other than ok
  double first_alarm_t = -1.0;               // [s] the first sample inconsistent or lost
  int alarms = 0;                            // times the state became inconsistent or lost
  double last_t = 0.0;
  Health last_health;
  EstimateRecord last_with_truth;

  // One sample's record (`first`: the start, whose step time is not a step's).
  void Add(const EstimateRecord& r, bool first) {
    if (!first) step_us.push_back(r.step_time_us);
    if (r.visual_ms >= 0.0) visual_ms.push_back(r.visual_ms), features_used += r.visual_used;
    constraints += r.constraints;
    penetration_sum += r.penetration;
    penetration_max = std::max(penetration_max, r.penetration);
    penetration_last = r.penetration;
    unexplained_sum += r.unexplained_torque;
    unexplained_max = std::max(unexplained_max, r.unexplained_torque);
    const double dt = first ? 0.0 : r.t - last_t;
    last_t = r.t;
    health_time[static_cast<std::size_t>(r.health.state)] += dt;
    if (r.health.state != HealthState::kOk) cause_time[HealthCauseName(r.health.cause)] += dt;
    const bool alarm = r.health.state >= HealthState::kInconsistent;
    if (alarm && (first || last_health.state < HealthState::kInconsistent)) {
      ++alarms;
      if (first_alarm_t < 0.0) first_alarm_t = r.t;
    }
    last_health = r.health;
    if (std::isfinite(r.nees)) nees.push_back(r.nees);
    if (std::isfinite(r.position_error)) {
      sq_pos += r.position_error * r.position_error;
      sq_ori += r.orientation_error * r.orientation_error;
      ++with_truth;
      last_with_truth = r;
    }
  }
};

// estimates.csv's header: the pose, its sigma, the errors, the deepest link inside the estimate,
// the torque its contacts leave unexplained, its health and why, how far the object is from the
// pressing finger most in the air (sets with torques, when a finger presses), then one bias per
// joint.
void WriteEstimatesHeader(std::ostream& csv, const Session& session) {
  csv << "t,set,px,py,pz,qw,qx,qy,qz,sigma_px,sigma_py,sigma_pz,sigma_rx,sigma_ry,sigma_rz,"
         "position_error_mm,orientation_error_deg,penetration_mm,unexplained_torque_Nm,health,"
         "health_cause,pressing_gap_mm";
  for (const std::string& n : session.joint_names()) csv << ",bias:" << n;
  csv << "\n";
}

// One row of estimates.csv. The filter lets nothing non-finite into its state; should it ever,
// no output pretends otherwise.
void WriteEstimate(std::ostream& csv, const std::string& session, const ModalitySet& set,
                   const EstimateRecord& r) {
  if (!r.T_PO.matrix().allFinite() || !r.sigma_position.allFinite() ||
      !r.sigma_orientation.allFinite())
    throw InputError(session + ": set " + set.name + " has a non-finite estimate at t = " +
                     FormatDouble(r.t) + " s (a bug: please report it with this session)");
  const Quat q(r.T_PO.linear());
  const Vec3& p = r.T_PO.translation();
  csv << FormatDouble(r.t) << "," << set.name;
  for (double v : {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z(), r.sigma_position.x(),
                   r.sigma_position.y(), r.sigma_position.z(), r.sigma_orientation.x(),
                   r.sigma_orientation.y(), r.sigma_orientation.z()})
    csv << "," << FormatDouble(v);
  csv << "," << (std::isfinite(r.position_error) ? FormatDouble(r.position_error * 1000) : "")
      << ","
      << (std::isfinite(r.orientation_error) ? FormatDouble(r.orientation_error * 180 / M_PI) : "")
      << "," << FormatDouble(r.penetration * 1000) << "," << FormatDouble(r.unexplained_torque)
      << "," << HealthStateName(r.health.state) << "," << HealthCauseName(r.health.cause) << ","
      << (r.press.pressing ? FormatDouble(r.press.gap * 1000) : "");
  for (long j = 0; j < r.biases.size(); ++j) csv << "," << FormatDouble(r.biases[j]);
  csv << "\n";
}

// events.csv: every set's events in time order (a set's own in the order found where times are
// equal), the message quoted.
void WriteEvents(const fs::path& path, const std::vector<ModalitySet>& sets,
                 const std::vector<std::vector<TrackerEvent>>& events, const HandModel& hand) {
  struct Row {
    double t;
    std::size_t set, index;
  };
  std::vector<Row> rows;
  for (std::size_t i = 0; i < events.size(); ++i)
    for (std::size_t j = 0; j < events[i].size(); ++j) rows.push_back({events[i][j].t, i, j});
  std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    return a.t != b.t ? a.t < b.t : a.set != b.set ? a.set < b.set : a.index < b.index;
  });
  std::ofstream csv(path);
  csv << "t,set,kind,subject,value,count,duration,message\n";
  for (const Row& row : rows) {
    const TrackerEvent& e = events[row.set][row.index];
    std::string message = EventMessage(e, hand), quoted = "\"";
    for (char c : message) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
    csv << FormatDouble(e.t) << "," << sets[row.set].name << "," << EventKindName(e.kind) << ","
        << EventSubject(e, hand) << "," << FormatDouble(e.value) << "," << e.count << ","
        << FormatDouble(e.duration) << "," << quoted << "\"\n";
  }
}

// summary.json's entry for one set: its costs, what its tracker did, and, against the ground
// truth, its errors and their consistency.
Json SetSummary(const ModalitySet& set, const SetStats& st, const TrackerStats& ts,
                const std::vector<TrackerEvent>& events, int n) {
  Json s = {
      {"torque", set.torque},
      {"tags", set.tags},
      {"features", set.features},
      {"step_time_us_median", Median(st.step_us)},
      {"step_time_us_p95", Percentile(st.step_us, 0.95)},
      {"visual_step_ms_median", st.visual_ms.empty() ? Json(nullptr) : Json(Median(st.visual_ms))},
      {"visual_updates", st.visual_ms.size()},
      {"features_used", st.features_used},
      {"constraints_per_step_mean", n ? double(st.constraints) / n : 0.0},
      // The deepest link inside the estimated object: over the samples, and at the end.
      {"penetration_mm_mean", n ? st.penetration_sum / n * 1000 : 0.0},
      {"penetration_mm_max", st.penetration_max * 1000},
      {"terminal_penetration_mm", st.penetration_last * 1000},
      // The torques the contacts at the estimate leave unexplained (sets with torques).
      {"unexplained_torque_Nm_mean", n ? st.unexplained_sum / n : 0.0},
      {"unexplained_torque_Nm_max", st.unexplained_max}};
  // Its health (filter/health.hpp): the share of the time in each state, the time spent in each
  // cause, the alarms (becoming inconsistent or lost) and the first one's time, the last state.
  {
    const double total =
        st.health_time[0] + st.health_time[1] + st.health_time[2] + st.health_time[3];
    // Sums of sample intervals: to the microsecond, without the sums' rounding noise.
    const auto micro = [](double v) { return std::round(v * 1e6) / 1e6; };
    Json share = Json::object();
    for (int k = 0; k < 4; ++k)
      share[HealthStateName(static_cast<HealthState>(k))] = micro(
          total > 0 ? st.health_time[static_cast<std::size_t>(k)] / total : (k == 0 ? 1.0 : 0.0));
    s["health_time_share"] = share;
    Json causes = Json::object();
    for (const auto& [cause, seconds] : st.cause_time) causes[cause] = micro(seconds);
    s["health_cause_seconds"] = causes;
    s["health_alarms"] = st.alarms;
    s["health_first_alarm_t"] = st.first_alarm_t >= 0.0 ? Json(st.first_alarm_t) : Json(nullptr);
    s["health_final"] = HealthStateName(st.last_health.state);
    s["health_final_cause"] = HealthCauseName(st.last_health.cause);
  }
  // Its events (events.csv), counted per kind, every kind listed.
  {
    std::array<long, kNumEventKinds> count{};
    for (const TrackerEvent& e : events) ++count[static_cast<std::size_t>(e.kind)];
    Json c = Json::object();
    for (int k = 0; k < kNumEventKinds; ++k)
      c[EventKindName(static_cast<EventKind>(k))] = count[static_cast<std::size_t>(k)];
    s["events"] = c;
  }
  s["images_fused"] = ts.images_fused;
  s["relocalizations"] = ts.relocalizations;
  s["recoveries"] = ts.recoveries;
  s["shifts_refused"] = ts.shifts_refused;
  s["images_features_lost"] = ts.images_features_lost;
  s["images_tags_elsewhere"] = ts.images_tags_elsewhere;
  s["images_dropped"] = ts.images_dropped_late + ts.images_dropped_busy + ts.images_rejected;
  s["joint_samples_dropped"] = ts.samples_dropped + ts.samples_rejected;
  if (st.with_truth == 0) return s;
  // At the last sample the ground truth covers.
  s["terminal_position_error_mm"] = st.last_with_truth.position_error * 1000;
  s["terminal_orientation_error_deg"] = st.last_with_truth.orientation_error * 180 / M_PI;
  const Vec3 dp = st.last_with_truth.position_error_O * 1000,
             dr = st.last_with_truth.orientation_error_O * (180 / M_PI);
  s["terminal_position_error_object_axes_mm"] = {dp.x(), dp.y(), dp.z()};
  s["terminal_orientation_error_object_axes_deg"] = {dr.x(), dr.y(), dr.z()};
  s["rms_position_error_mm"] = std::sqrt(st.sq_pos / st.with_truth) * 1000;
  s["rms_orientation_error_deg"] = std::sqrt(st.sq_ori / st.with_truth) * 180 / M_PI;
  // Consistency: the NEES of a consistent filter follows χ²₆ (mean 6; 95 % in [1.24, 14.45]).
  double mean = 0.0;
  long inside = 0;
  for (double v : st.nees) mean += v, inside += v >= 1.237 && v <= 14.449;
  s["nees_mean"] = st.nees.empty() ? 0.0 : mean / static_cast<double>(st.nees.size());
  s["nees_within_95_percent_bounds"] =
      st.nees.empty() ? 0.0 : double(inside) / static_cast<double>(st.nees.size());
  return s;
}

// The progress bar on a terminal: redrawn when the percentage changes.
class ProgressBar {
 public:
  explicit ProgressBar(const char* what = "replay") : what_(what), tty_(::isatty(STDERR_FILENO)) {}
  void Show(int k, int n) {
    const int percent = static_cast<int>(100.0 * k / n);
    if (!tty_ || (percent == shown_ && k != n)) return;
    shown_ = percent;
    const int width = 40, done = static_cast<int>(std::lround(width * double(k) / n));
    std::fprintf(stderr, "\r%-8s [%s%s] %3d%%", what_,
                 std::string(static_cast<std::size_t>(done), '#').c_str(),
                 std::string(static_cast<std::size_t>(width - done), ' ').c_str(), percent);
  }
  void End() {
    if (tty_) std::fprintf(stderr, "\n");
  }

 private:
  const char* what_;
  bool tty_;
  int shown_ = -1;
};

// The annotated pictures: drawn, encoded and written in capture order, on a thread of their own
// (jobs > 1: the player goes on meanwhile, at most `kQueued` pictures ahead) or inline.
class Pictures {
 public:
  using Emit = std::function<void(FrameComposer&, const PictureState&, int)>;
  Pictures(const SessionPlayer& player, bool threaded, Emit emit)
      : player_(player), emit_(std::move(emit)) {
    if (!threaded) {
      composer_ = std::make_unique<FrameComposer>(player_);
      return;
    }
    thread_ = std::thread([this] { Loop(); });
  }
  ~Pictures() {  // without Finish (the replay failed): the pictures not drawn yet are dropped
    if (thread_.joinable()) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        done_ = true;
        queue_.clear();
      }
      cv_.notify_all();
      thread_.join();
    }
  }
  void Add(PictureState state, int index) {
    if (!thread_.joinable()) return emit_(*composer_, state, index);
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [&] { return queue_.size() < kQueued || error_; });
    if (error_) std::rethrow_exception(error_);
    queue_.emplace_back(std::move(state), index);
    cv_.notify_all();
  }
  // Waits for every picture; rethrows what went wrong on the thread.
  void Finish() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    cv_.notify_all();
    thread_.join();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  static constexpr std::size_t kQueued = 2;
  void Loop() {
    try {
      FrameComposer composer(player_);  // its GL context lives on this thread
      for (;;) {
        std::pair<PictureState, int> job;
        {
          std::unique_lock<std::mutex> lock(mutex_);
          cv_.wait(lock, [&] { return done_ || !queue_.empty(); });
          if (queue_.empty()) return;
          job = std::move(queue_.front());
          queue_.pop_front();
          cv_.notify_all();
        }
        emit_(composer, job.first, job.second);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
      queue_.clear();
      cv_.notify_all();
    }
  }
  const SessionPlayer& player_;
  Emit emit_;
  std::unique_ptr<FrameComposer> composer_;  // inline
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::pair<PictureState, int>> queue_;
  bool done_ = false;
  std::exception_ptr error_;
};

// A held picture's camera image, read again from the session (the one the trackers read): the
// states are held without it, which halves their memory.
void ReadCameraImage(const SessionPlayer& player, PictureState& state) {
  if (state.camera_frame >= 0 && state.camera.empty())
    state.camera = player.session().LoadImage(state.camera_frame);
}

// Pictures held until the session's events were known, drawn on `threads` composers of their own
// (each renderer on its thread; 1: inline), at most kAhead pictures ahead of the one written next,
// and written in order. Each state is freed once drawn.
void DrawHeld(const SessionPlayer& player, std::vector<std::pair<PictureState, int>>& held,
              int threads, const std::function<Image8(FrameComposer&, const PictureState&)>& draw,
              const std::function<void(const Image8&, int)>& write) {
  const std::size_t count = held.size();
  if (threads <= 1 || count < 2) {
    FrameComposer composer(player);
    for (auto& [state, index] : held) {
      ReadCameraImage(player, state);
      write(draw(composer, state), index);
      state = PictureState();
    }
    return;
  }
  constexpr std::size_t kAhead = 8;
  std::vector<std::optional<Image8>> drawn(count);
  std::mutex mutex, creating;
  std::condition_variable cv;
  std::size_t written = 0;
  bool stop = false;
  std::exception_ptr error;
  const auto fail = [&](std::exception_ptr e) {  // the first failure stops every thread
    std::lock_guard<std::mutex> lock(mutex);
    if (!error) error = e;
    stop = true;
    cv.notify_all();
  };
  std::vector<std::thread> workers;
  for (int w = 0; w < threads; ++w)
    workers.emplace_back([&, w] {
      try {
        std::unique_ptr<FrameComposer> composer;
        {  // one context created at a time: the first one sets the renderer library up
          std::lock_guard<std::mutex> lock(creating);
          composer = std::make_unique<FrameComposer>(player);  // its GL context: this thread's
        }
        for (std::size_t i = static_cast<std::size_t>(w); i < count;
             i += static_cast<std::size_t>(threads)) {
          {
            std::unique_lock<std::mutex> lock(mutex);
            cv.wait(lock, [&] { return stop || i < written + kAhead; });
            if (stop) return;
          }
          ReadCameraImage(player, held[i].first);
          Image8 picture = draw(*composer, held[i].first);
          held[i].first = PictureState();
          std::lock_guard<std::mutex> lock(mutex);
          drawn[i] = std::move(picture);
          cv.notify_all();
        }
      } catch (...) {
        fail(std::current_exception());
      }
    });
  try {
    for (std::size_t i = 0; i < count; ++i) {
      Image8 picture;
      {
        std::unique_lock<std::mutex> lock(mutex);
        cv.wait(lock, [&] { return stop || drawn[i].has_value(); });
        if (stop) break;
        picture = std::move(*drawn[i]);
        drawn[i].reset();
      }
      write(picture, held[i].second);
      std::lock_guard<std::mutex> lock(mutex);
      ++written;
      cv.notify_all();
    }
  } catch (...) {
    fail(std::current_exception());
  }
  for (std::thread& t : workers) t.join();
  if (error) std::rethrow_exception(error);
}

// Every set's events over the whole session, found by a replay of its own without pictures
// (deterministic: the same events the replay proper will find), for the video's timeline strip,
// which shows them before they come.
std::vector<std::vector<TrackerEvent>> EventsAhead(const SessionPlayer& like, int jobs) {
  SessionPlayer player(like.session(), like.params(), like.sets());
  std::vector<std::vector<TrackerEvent>> events(player.sets().size());
  std::vector<EstimateRecord> records;
  const int n = player.num_samples();
  for (int k = 0; k < n;) {
    const int count = player.StepBlock(k, 256, jobs, records);
    for (std::size_t j = 0; j < records.size(); ++j) {  // sample-major
      const std::vector<TrackerEvent>& found = records[j].events;
      events[j % events.size()].insert(events[j % events.size()].end(), found.begin(), found.end());
    }
    k += count;
  }
  for (std::size_t i = 0; i < events.size(); ++i) player.CloseEvents(i, events[i]);
  return events;
}

// The memory that the pictures' states of the whole session take when held for the timeline: per
// picture the matched virtual view (RGB; the camera image is read again when drawn), and up to
// 64 KiB per set for its traces.
double HeldPictureBytes(const Session& session, const std::vector<ModalitySet>& sets, double fps,
                        bool has_camera) {
  const int n = session.num_samples();
  const double pictures = has_camera ? double(session.camera_frames().size())
                                     : std::floor((session.t(n - 1) - session.t(0)) * fps) + 2.0;
  double per_picture = 64.0 * 1024 * double(sets.size());
  if (has_camera && sets.back().features)
    per_picture += 3.0 * session.info().camera->width * session.info().camera->height;
  return pictures * per_picture;
}

}  // namespace

// What the replay wrote, and per set its terminal error (against the truth) and median step.
void PrintOutcome(const Session& session, const std::string& out,
                  const std::vector<ModalitySet>& sets, const Json& per_set) {
  const int n = session.num_samples();
  const auto& frames = session.camera_frames();
  std::cout << "replay of " << session.info().name << " (" << n << " samples, " << frames.size()
            << " frames) written to " << out << "\n";
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const Json& s = per_set[sets[i].name];
    std::cout << "  " << sets[i].name << ": ";
    if (s.contains("terminal_position_error_mm"))
      std::cout << "terminal error " << std::fixed << std::setprecision(1)
                << s["terminal_position_error_mm"].get<double>() << " mm / "
                << s["terminal_orientation_error_deg"].get<double>() << " deg, ";
    std::cout << "median step " << std::setprecision(0) << s["step_time_us_median"].get<double>()
              << " us\n";
  }
}

int RunReplay(const ReplayCommand& cmd) {
  if (cmd.out.empty()) throw InputError("replay: --out DIR is required");
  Session session = Session::Load(cmd.session);
  TrackerParams params;
  if (!cmd.params.empty()) params = ReadTrackerParams(cmd.params);
  SessionPlayer player(
      session, params,
      cmd.modalities.empty() ? std::vector<ModalitySet>() : ParseModalities(cmd.modalities));
  const std::vector<ModalitySet>& sets = player.sets();
  const bool has_camera = session.info().camera.has_value();
  // Without a camera the video is the external 3-D view at --video-fps.
  const bool want_pictures = !cmd.no_video || cmd.frames;
  if (!(cmd.video_fps > 0.0 && cmd.video_fps <= 240.0))
    throw InputError("--video-fps: expected a rate in (0, 240] Hz");
  if (!(cmd.picture_memory_mib >= 0.0 && cmd.picture_memory_mib <= 1e6))
    throw InputError("--picture-memory: expected MiB in [0, 1e6]");
  if (cmd.jobs < 1 || cmd.jobs > 64)
    throw InputError("--jobs is " + std::to_string(cmd.jobs) + ", expected 1..64");
  for (const std::string& w :
       player.input_report().Warnings(session, player.models(), player.params()))
    std::cerr << "inhand: warning: " << w << "\n";

  StagedOutput out(cmd.out, {cmd.session, cmd.params}, "replay");
  if (cmd.frames) fs::create_directories(out / "frames");
  std::ofstream csv(out / "estimates.csv");
  WriteEstimatesHeader(csv, session);

  std::unique_ptr<VideoWriter> video;
  std::unique_ptr<McapExport> mcap;
  if (cmd.mcap) mcap = std::make_unique<McapExport>((out / "replay.mcap").string(), player);
  const auto& frames = session.camera_frames();
  const int n = session.num_samples();
  const double fps = !has_camera         ? cmd.video_fps
                     : frames.size() > 1 ? 1.0 / (frames[1].t - frames[0].t)
                                         : 10.0;
  double next_picture_t = n > 0 ? session.t(0) : 0.0;
  int pictures = 0;
  // Under every picture, the session's timeline with its events and the current time.
  std::optional<TimelineStrip> timeline;
  std::unique_ptr<TimelineStripPainter> strip;  // painted at the first picture, as wide
  std::once_flag strip_painted;
  const auto draw = [&](FrameComposer& composer, const PictureState& state) {
    Image8 picture = has_camera ? composer.Compose(state) : composer.ComposeExternal(state);
    if (timeline) {
      std::call_once(strip_painted, [&] {
        strip = std::make_unique<TimelineStripPainter>(*timeline, picture.width);
      });
      picture = StackBelow(picture, strip->At(state.t));
    }
    return picture;
  };
  const auto write = [&](const Image8& picture, int index) {
    if (!cmd.no_video) {
      if (!video)
        video = std::make_unique<VideoWriter>((out / "replay.mp4").string(), fps, picture.width,
                                              picture.height);
      video->Write(picture);
    }
    if (cmd.frames) {
      char name[64];
      std::snprintf(name, sizeof(name), "frames/frame_%06d.png", index);
      WriteImage((out / name).string(), picture);
    }
  };
  const auto emit = [&](FrameComposer& composer, const PictureState& state, int index) {
    write(draw(composer, state), index);
  };
  // The timeline strip needs every event before the first picture. When the pictures' states fit
  // in --picture-memory, they are held through the one pass and drawn after it, with the events
  // that pass found; otherwise a pass of its own without pictures finds the events first.
  const bool want_timeline = want_pictures && !cmd.no_timeline && n > 0;
  const bool hold = want_timeline && HeldPictureBytes(session, sets, fps, has_camera) <=
                                         cmd.picture_memory_mib * double(1 << 20);
  std::vector<std::pair<PictureState, int>> held;
  if (want_timeline && !hold)
    timeline =
        MakeTimelineStrip(sets, EventsAhead(player, cmd.jobs), session.t(0), session.t(n - 1));
  std::unique_ptr<Pictures> drawn;
  if (want_pictures && !hold) drawn = std::make_unique<Pictures>(player, cmd.jobs > 1, emit);
  const auto add_picture = [&](PictureState state, int index) {
    if (hold)
      held.emplace_back(std::move(state), index);
    else
      drawn->Add(std::move(state), index);
  };
  std::vector<SetStats> stats(sets.size());
  std::vector<std::vector<TrackerEvent>> events(sets.size());
  std::vector<EstimateRecord> records;
  ProgressBar progress;
  const auto wall_start = std::chrono::steady_clock::now();
  for (int k = 0; k < n;) {
    // A block of samples up to the next camera frame (or the next picture of the 3-D view).
    int max_samples = 256;
    if (want_pictures && !has_camera) {
      int j = k;
      while (j < n - 1 && session.t(j) < next_picture_t - kTimeTolerance) ++j;
      max_samples = std::min(max_samples, j - k + 1);
    }
    const int count = player.StepBlock(k, max_samples, cmd.jobs, records);
    for (int s = k; s < k + count; ++s) {
      const EstimateRecord* row = &records[static_cast<std::size_t>(s - k) * sets.size()];
      for (std::size_t i = 0; i < sets.size(); ++i) {
        WriteEstimate(csv, cmd.session, sets[i], row[i]);
        stats[i].Add(row[i], s == 0);
        events[i].insert(events[i].end(), row[i].events.begin(), row[i].events.end());
      }
      // Only the block's last sample captures frames; the player stands there.
      if (mcap) mcap->AddSample(s, row, s == k + count - 1 ? player.last_frame() : -1);
    }
    k += count;
    const double t = session.t(k - 1);
    // The camera frame the block's last sample processed, if any.
    if (const int frame = player.last_frame(); frame >= 0 && want_pictures && has_camera)
      add_picture(FrameComposer::Capture(player, frame, t, !hold), frame);  // held: read later
    // No camera: a picture of the 3-D view whenever the video's clock passes a sample.
    if (want_pictures && !has_camera && t >= next_picture_t - kTimeTolerance) {
      add_picture(FrameComposer::Capture(player, -1, t), pictures++);
      next_picture_t = session.t(0) + pictures / fps;
    }
    progress.Show(k, n);
  }
  if (drawn) drawn->Finish();
  progress.End();
  // The bursts still open at the end.
  for (std::size_t i = 0; i < sets.size(); ++i) {
    std::vector<TrackerEvent> closed;
    player.CloseEvents(i, closed);
    if (mcap && n > 0) mcap->AddEvents(i, closed, session.t(n - 1));
    events[i].insert(events[i].end(), closed.begin(), closed.end());
  }
  if (hold) {  // the held pictures, now that every event is known
    timeline = MakeTimelineStrip(sets, events, session.t(0), session.t(n - 1));
    ProgressBar drawing("pictures");
    const int count = static_cast<int>(held.size());
    int done = 0;
    DrawHeld(player, held, std::min(cmd.jobs, 4), draw, [&](const Image8& picture, int index) {
      write(picture, index);
      drawing.Show(++done, count);
    });
    drawing.End();
  }
  WriteEvents(out / "events.csv", sets, events, player.models().hand);
  if (video) video->Close();
  if (mcap) mcap->Close();
  csv.close();

  Json summary = {
      {"session", fs::absolute(cmd.session).lexically_normal().string()},
      {"session_name", session.info().name},
      {"samples", n},
      {"camera_frames", frames.size()},
      {"video", video ? "replay.mp4" : Json(nullptr)},
      {"mcap", mcap ? "replay.mcap" : Json(nullptr)},
      {"wall_time_s",
       std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count()},
      {"parameters", Json::parse(TrackerParamsToJson(player.params()))},
      // What the sets with torques undeflected the joints with (null: rigid joints).
      {"joint_stiffness", session.info().joint_stiffness.empty()
                              ? Json(nullptr)
                              : Json(session.info().joint_stiffness)},
      {"joint_samples_rejected", player.input_report().rejected_samples.size()},
      {"frames_before_first_sample", player.input_report().frames_before_first_sample},
      {"samples_without_truth", player.input_report().samples_without_truth}};
  Json per_set = Json::object();
  for (std::size_t i = 0; i < sets.size(); ++i)
    per_set[sets[i].name] = SetSummary(sets[i], stats[i], player.tracker(i).stats(), events[i], n);
  summary["modalities"] = per_set;
  std::ofstream(out / "summary.json") << summary.dump(2) << "\n";
  std::ofstream(out / "params.json") << TrackerParamsToJson(player.params()) << "\n";
  out.Commit();

  PrintOutcome(session, cmd.out, sets, per_set);
  return 0;
}

}  // namespace inhand::app
