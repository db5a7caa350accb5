#include "annotator.hpp"

#include <exception>

#include "inhand/app/modalities.hpp"
#include "inhand/renderer/printed_tags.hpp"
#include "inhand/renderer/views.hpp"

namespace inhand::ros {

Annotator::Annotator(const ObjectModel& object, Publish publish)
    : object_(object), publish_(std::move(publish)), thread_([this] { Run(); }) {}

Annotator::~Annotator() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void Annotator::Request(AnnotationRequest request) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    waiting_ = std::move(request);
  }
  wake_.notify_all();
}

long Annotator::drawn() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return drawn_;
}

std::string Annotator::error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

Image8 Annotator::Draw(OverlayPainter& painter, const AnnotationRequest& request) {
  OverlayFrame frame;
  frame.camera = request.camera;
  frame.T_PC = request.T_PC;
  frame.K = request.K;
  for (std::size_t i = 0; i < request.sets.size(); ++i) {
    const Rgb colour = app::ModalityColour(request.names[i]);
    frame.estimates.push_back(app::OverlayOf(request.names[i], colour, request.sets[i]));
    frame.hud.push_back(app::HudLine(request.names[i], request.sets[i]));
  }
  return painter.Paint(frame);
}

void Annotator::Run() {
  try {
    Renderer renderer;
    OverlayPainter painter(renderer, UploadObject(renderer, object_, PrintedTagMeshes(object_)));
    for (;;) {
      AnnotationRequest request;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || waiting_; });
        if (stop_) return;
        request = std::move(*waiting_);
        waiting_.reset();
      }
      const Image8 picture = Draw(painter, request);
      publish_(request, picture);
      std::lock_guard<std::mutex> lock(mutex_);
      ++drawn_;
    }
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = e.what();
  }
}

}  // namespace inhand::ros
