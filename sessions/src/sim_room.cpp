#include "sim_room.hpp"

#include <cmath>
#include <random>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "inhand/core/mesh.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand::sim {
namespace {

// A flat textured rectangle (table top, backdrop) with a procedural pattern.
TriangleMesh TexturedBox(const Vec3& half, const cv::Mat& texture_bgr) {
  TriangleMesh m = ConvexPiece::Box(half, Transform::Identity()).ToMesh();
  m.uvs.clear();
  for (const Vec3& v : m.vertices)
    m.uvs.emplace_back(0.5 + 0.5 * v.x() / half.x(), 0.5 + 0.5 * v.y() / half.y());
  Image8 rgb(texture_bgr.cols, texture_bgr.rows, 3);
  cv::Mat out(rgb.height, rgb.width, CV_8UC3, rgb.data.data());
  cv::cvtColor(texture_bgr, out, cv::COLOR_BGR2RGB);
  m.material.texture_blob = EncodePng(rgb);
  m.material.rgba = Eigen::Vector4d(1, 1, 1, 1);
  return m;
}

cv::Mat WoodTexture() {
  cv::Mat t(256, 256, CV_8UC3);
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x) {
      const double g =
          0.5 + 0.5 * std::sin(0.09 * x + 2.5 * std::sin(0.021 * y) + 0.7 * std::sin(0.13 * y));
      t.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<std::uint8_t>(70 + 25 * g), static_cast<std::uint8_t>(110 + 30 * g),
                    static_cast<std::uint8_t>(150 + 35 * g));
    }
  return t;
}

cv::Mat ClutterTexture(std::mt19937& rng) {
  cv::Mat t(512, 512, CV_8UC3, cv::Scalar(200, 205, 210));
  std::uniform_int_distribution<int> pos(0, 511), size(20, 140), colour(30, 240);
  for (int i = 0; i < 60; ++i)
    cv::rectangle(t, cv::Rect(pos(rng), pos(rng), size(rng), size(rng)),
                  cv::Scalar(colour(rng), colour(rng), colour(rng)), cv::FILLED);
  return t;
}

}  // namespace

Scene BuildRoom(Renderer& renderer, const Scenario& scenario, int occluders, const Intrinsics& K,
                const Transform& T_WC) {
  Scene room;
  std::mt19937 clutter_rng(12345);  // the same room for every seed
  room.K = K;
  room.T_PC = T_WC;
  room.background = Vec3(0.55, 0.58, 0.62);
  const int table = renderer.AddMesh(TexturedBox(Vec3(0.6, 0.4, 0.025), WoodTexture()));
  room.items.push_back({table, MakeTransform(Vec3(0, 0, -0.025), Mat3::Identity()), kExtraLabelBase,
                        std::nullopt, 1.0, false});
  const int wall = renderer.AddMesh(TexturedBox(Vec3(0.8, 0.5, 0.01), ClutterTexture(clutter_rng)));
  room.items.push_back({wall, MakeTransform(Vec3(-0.1, 0.45, 0.3), ExpSO3(Vec3(M_PI / 2, 0, 0))),
                        kExtraLabelBase + 1, std::nullopt, 1.0, false});
  for (const Scenario::Prop& p : scenario.props) {
    TriangleMesh mesh = ConvexPiece::Box(p.half_extents, Transform::Identity()).ToMesh();
    mesh.material.rgba = p.rgba;
    room.items.push_back({renderer.AddMesh(mesh), p.T_W,
                          static_cast<std::uint16_t>(kExtraLabelBase + 50), std::nullopt, 1.0,
                          false});
  }
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 6 + occluders; ++i) {
    const bool occluder = i >= 6;
    TriangleMesh mesh =
        i % 2 ? ConvexPiece::Cylinder(0.02 + 0.03 * u(clutter_rng), 0.03 + 0.05 * u(clutter_rng),
                                      Transform::Identity())
                    .ToMesh()
              : ConvexPiece::Box(Vec3(0.02 + 0.04 * u(clutter_rng), 0.02 + 0.04 * u(clutter_rng),
                                      0.03 + 0.04 * u(clutter_rng)),
                                 Transform::Identity())
                    .ToMesh();
    mesh.material.rgba = Eigen::Vector4d(0.2 + 0.7 * u(clutter_rng), 0.2 + 0.7 * u(clutter_rng),
                                         0.2 + 0.7 * u(clutter_rng), 1.0);
    const int id = renderer.AddMesh(mesh);
    const double h = mesh.Bounds().Size().z() / 2;
    Vec3 where;
    if (occluder) {  // between the camera and the grasp, low in the view
      where = scenario.camera_target +
              (scenario.camera_eye - scenario.camera_target) * (0.35 + 0.1 * i / 8.0);
      where.x() += (i % 2 ? 0.05 : -0.05);
      where.z() = h;
    } else {
      const double a = -0.6 + 1.3 * i / 6.0;
      where = Vec3(-0.35 + 0.14 * i, 0.25 + 0.06 * std::cos(a * 2.0), h);
    }
    room.items.push_back({id, MakeTransform(where, ExpSO3(Vec3(0, 0, 0.4 * i))),
                          static_cast<std::uint16_t>(kExtraLabelBase + 2 + i), std::nullopt, 1.0,
                          false});
  }
  return room;
}

}  // namespace inhand::sim
