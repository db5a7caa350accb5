#pragma once
// The node's annotated camera image (the paper's Fig. 1): each set's estimate drawn over the
// newest image the trackers used, as a translucent silhouette with its outline, position σ,
// contacts, forces and feature matches, and a HUD line per set (the replay video's words). Drawn
// on a thread of its own with its own renderer (an OpenGL context belongs to one thread), so that
// the joint states never wait for a drawing; a request made while one is drawn replaces the one
// waiting.
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "inhand/app/frame_composer.hpp"
#include "inhand/core/object_model.hpp"

namespace inhand::ros {

// What one picture shows, copied on the joint states' thread.
struct AnnotationRequest {
  std::int64_t stamp_ns = 0;  // the image's
  std::string frame_id;       // the image's
  Image8 camera;
  Transform T_PC = Transform::Identity();
  Intrinsics K;
  std::vector<std::string> names;
  std::vector<app::PictureState::Set> sets;
};

class Annotator {
 public:
  using Publish = std::function<void(const AnnotationRequest& request, const Image8& picture)>;
  // `object` must outlive this; `publish` is called on the annotator's thread.
  Annotator(const ObjectModel& object, Publish publish);
  ~Annotator();  // finishes the picture being drawn, drops the one waiting
  Annotator(const Annotator&) = delete;
  Annotator& operator=(const Annotator&) = delete;

  void Request(AnnotationRequest request);
  long drawn() const;
  // The first error of the drawing thread (no OpenGL context, ...); empty when none.
  std::string error() const;

  // The picture itself, on the calling thread (tests, and the thread above).
  static Image8 Draw(OverlayPainter& painter, const AnnotationRequest& request);

 private:
  void Run();
  const ObjectModel& object_;
  Publish publish_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<AnnotationRequest> waiting_;
  bool stop_ = false;
  long drawn_ = 0;
  std::string error_;
  std::thread thread_;
};

}  // namespace inhand::ros
