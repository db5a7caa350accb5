// What `inhand import` says: the report of an import, and the listing of a recording (--list).
#include <algorithm>
#include <iomanip>
#include <sstream>

#include "inhand/ros/import.hpp"
#include "inhand/ros/recording.hpp"
#include "inhand/ros/tf_tree.hpp"

namespace inhand::ros {
namespace {

std::string Seconds(double s) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(3) << s;
  return o.str();
}

}  // namespace

std::vector<std::string> ImportReport::Summary() const {
  std::vector<std::string> out;
  const double span = t_last - t_first;
  std::ostringstream j;
  j << "joints: " << samples << " samples from " << joints_topic << " (" << joint_messages
    << " messages), " << Seconds(span) << " s";
  if (span > 0 && samples > 1) j << " at " << std::setprecision(4) << (samples - 1) / span << " Hz";
  j << (torques ? ", with external torques" : ", no torques");
  out.push_back(j.str());
  if (out_of_order + duplicates + non_finite + outside_window > 0)
    out.push_back("  dropped: " + std::to_string(duplicates) + " duplicate stamps, " +
                  std::to_string(non_finite) + " with non-finite values, " +
                  std::to_string(outside_window) + " outside --start/--end; " +
                  std::to_string(out_of_order) + " out of order (sorted)");
  if (!image_topic.empty()) {
    out.push_back("images: " + std::to_string(frames) + " frames from " + image_topic + " (" +
                  std::to_string(image_messages) + " messages), camera " + camera_frame + " in " +
                  palm_frame + " from TF, intrinsics from " + camera_info_topic);
    if (frames_without_tf + frame_duplicates > 0)
      out.push_back("  dropped: " + std::to_string(frames_without_tf) +
                    " without TF at their stamp, " + std::to_string(frame_duplicates) +
                    " duplicate stamps");
  } else {
    out.push_back("images: none");
  }
  if (!object_pose_topic.empty())
    out.push_back("ground truth: " + std::to_string(truth_samples) + " poses from " +
                  object_pose_topic + " (" + std::to_string(truth_messages) + " messages, " +
                  std::to_string(truth_without_tf) + " without TF dropped)");
  out.push_back("time: t = 0 is stamp " + std::to_string(origin_ns / 1000000000) + "." + [&] {
    std::ostringstream o;
    o << std::setw(9) << std::setfill('0') << origin_ns % 1000000000;
    return o.str();
  }() + " s; " + format);
  return out;
}

std::string ListRecording(const std::string& path) {
  std::unique_ptr<Recording> rec = OpenRecording(path);
  const std::vector<TopicInfo> topics = rec->Topics();
  std::ostringstream out;
  out << rec->path() << ": " << rec->format() << ", " << topics.size() << " topics\n";
  std::size_t w = 5, wt = 4;
  for (const TopicInfo& t : topics)
    w = std::max(w, t.name.size()), wt = std::max(wt, t.type.size());
  out << std::left << std::setw(static_cast<int>(w) + 2) << "topic"
      << std::setw(static_cast<int>(wt) + 2) << "type" << std::right << std::setw(9) << "messages"
      << std::setw(11) << "rate [Hz]" << std::setw(11) << "span [s]"
      << "\n";
  std::vector<std::string> tf_topics;
  std::int64_t first = 0;
  for (const TopicInfo& t : topics)
    if (t.count > 0) first = first == 0 ? t.first_ns : std::min(first, t.first_ns);
  for (const TopicInfo& t : topics) {
    out << std::left << std::setw(static_cast<int>(w) + 2) << t.name
        << std::setw(static_cast<int>(wt) + 2) << t.type << std::right << std::setw(9) << t.count
        << std::setw(11) << std::fixed << std::setprecision(1) << t.Rate() << std::setw(11)
        << std::setprecision(3) << (t.count > 0 ? (t.last_ns - t.first_ns) * 1e-9 : 0.0) << "\n";
    if (MsgTypeOf(t.type) == MsgType::kTf) tf_topics.push_back(t.name);
  }
  TfTree tree;
  rec->Read(tf_topics, false, [&](Message& m) {
    const bool is_static = m.topic->find("static") != std::string::npos;
    for (const StampedTransform& t : std::get<TfMsg>(m.payload).transforms) tree.Add(t, is_static);
  });
  tree.Finish();
  const auto edges = tree.Edges();
  if (edges.empty()) {
    out << "TF: none (no /tf or /tf_static): the camera's pose cannot be imported from this "
           "recording\n";
  } else {
    out << "TF frames (frame <- parent):\n";
    for (const auto& [child, e] : edges)
      out << "  " << child << " <- " << e.parent
          << (e.is_static ? "  (static)" : "  (" + std::to_string(e.samples) + " transforms)")
          << "\n";
    if (tree.conflicts() > 0)
      out << "  (" << tree.conflicts() << " transforms gave a frame a second parent; ignored)\n";
  }
  return out.str();
}

}  // namespace inhand::ros
