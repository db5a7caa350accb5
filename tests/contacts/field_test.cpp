// Penetration against the object as a whole (issue 15): a sphere and a capsule pushed into one
// convex solid, the same solid cut into 2, 8 and 64 pieces, and the YCB scans with their VHACD
// pieces. The reference is computed here, independently of the field: brute-force distance to
// every triangle of the watertight surface, the sign from the generalised winding number.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/error.hpp"
#include "inhand/io/mesh_io.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

namespace fs = std::filesystem;

using Tri = std::array<Vec3, 3>;

// Signed distance to a closed triangle soup: brute force, sign by the winding number
// (Van Oosterom & Strackee's solid angle per triangle).
struct MeshOracle {
  std::vector<Tri> tris;

  explicit MeshOracle(const std::vector<const TriangleMesh*>& meshes) {
    for (const TriangleMesh* m : meshes)
      for (const auto& t : m->triangles)
        tris.push_back({m->vertices[t[0]], m->vertices[t[1]], m->vertices[t[2]]});
  }

  double Winding(const Vec3& p) const {
    double sum = 0.0;
    for (const Tri& t : tris) {
      const Vec3 a = t[0] - p, b = t[1] - p, c = t[2] - p;
      const double la = a.norm(), lb = b.norm(), lc = c.norm();
      const double num = a.dot(b.cross(c));
      const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
      sum += 2.0 * std::atan2(num, den);
    }
    return sum / (4.0 * M_PI);
  }

  // Signed distance and outward normal (from the closest point).
  double Signed(const Vec3& p, Vec3* normal = nullptr) const {
    double best = std::numeric_limits<double>::infinity();
    Vec3 closest = Vec3::Zero();
    for (const Tri& t : tris) {
      Vec3 q;
      const double d = PointTriangleDistance(p, t[0], t[1], t[2], &q);
      if (d < best) best = d, closest = q;
    }
    const bool inside = Winding(p) > 0.5;
    if (normal) *normal = ((inside ? closest - p : p - closest)).normalized();
    return inside ? -best : best;
  }
};

// A hand of two links fixed to the palm: a sphere (a fingertip) and a capsule (a phalanx).
constexpr const char* kProbes = R"(<robot name="probes">
  <link name="palm"/>
  <link name="tip"><collision><geometry><sphere radius="0.008"/></geometry></collision></link>
  <link name="phalanx"><collision><geometry><sphere radius="0.006"/></geometry></collision></link>
  <joint name="a" type="fixed"><parent link="palm"/><child link="tip"/></joint>
  <joint name="b" type="fixed"><parent link="palm"/><child link="phalanx"/></joint>
</robot>)";

HandModel ProbeHand(double tip_radius) {
  HandModel hand = ParseHandModel(kProbes, ".", "probes.urdf");
  hand.links[static_cast<std::size_t>(hand.LinkIndex("tip"))].collision = {
      ConvexPiece::Sphere(tip_radius, Transform::Identity())};
  // Capsule along the link's z: half-length 10 mm, radius 6 mm.
  hand.links[static_cast<std::size_t>(hand.LinkIndex("phalanx"))].collision = {
      ConvexPiece::Capsule(0.006, 0.010, Transform::Identity())};
  return hand;
}

// The exact answer for one probe placed at `T_PL` against the object at the origin.
struct Exact {
  double distance;
  Vec3 normal;          // outward, object frame
  bool normal_defined;  // false near the medial axis (the exact normal turns by more than 10
                        // degrees within 1.5 mm: 1.5 grid steps, where no grid can resolve it)
};

Exact ExactSphere(const MeshOracle& oracle, const Vec3& centre, double radius) {
  Exact e;
  e.distance = oracle.Signed(centre, &e.normal) - radius;
  e.normal_defined = true;
  for (const Vec3& step : {Vec3(1.5e-3, 0, 0), Vec3(0, 1.5e-3, 0), Vec3(0, 0, 1.5e-3),
                           Vec3(-1.5e-3, 0, 0), Vec3(0, -1.5e-3, 0), Vec3(0, 0, -1.5e-3)}) {
    Vec3 n;
    oracle.Signed(centre + step, &n);
    if (n.dot(e.normal) < std::cos(10.0 * M_PI / 180.0)) e.normal_defined = false;
  }
  return e;
}

Exact ExactCapsule(const MeshOracle& oracle, const Vec3& a, const Vec3& b, double radius) {
  // Every 1 mm along the segment, then every 0.1 mm around the best sample.
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 1e-3)));
  double best = std::numeric_limits<double>::infinity();
  double at = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double d = oracle.Signed(a + (b - a) * (double(i) / n));
    if (d < best) best = d, at = double(i) / n;
  }
  const double centre = at;
  for (int i = -9; i <= 9; ++i) {
    const double u = std::clamp(centre + i * 0.1 / n, 0.0, 1.0);
    const double d = oracle.Signed(a + (b - a) * u);
    if (d < best) best = d, at = u;
  }
  return ExactSphere(oracle, a + (b - a) * at, radius);
}

struct Sweep {
  std::vector<double> measured, exact, angle_deg;
  std::vector<bool> normal_checked;
};

// Pushes link `link` of `hand` from `start` along `dir` (steps of `step`), returning the query's
// distance and the exact one at each position.
Sweep Push(const HandModel& hand, const ObjectModel& object, const MeshOracle& oracle,
           const char* link, const Vec3& start, const Vec3& dir, double step, int steps) {
  BulletContactQuery query(hand, object);
  const int l = hand.LinkIndex(link);
  const ConvexPiece& piece = hand.links[static_cast<std::size_t>(l)].collision[0];
  Sweep s;
  std::vector<ContactPair> pairs;
  for (int k = 0; k < steps; ++k) {
    const Vec3 c = start + dir * (k * step);
    std::vector<Transform> T_PL(hand.links.size(),
                                MakeTransform(Vec3(10, 10, 10), Mat3::Identity()));
    T_PL[static_cast<std::size_t>(l)] = MakeTransform(c, Mat3::Identity());
    query.Query(T_PL, Transform::Identity(), 0.05, pairs);
    ContactPair got;
    got.distance = std::numeric_limits<double>::infinity();
    for (const ContactPair& p : pairs)
      if (p.link == l) got = p;
    const Exact e = piece.kind == ConvexPiece::Kind::kSphere
                        ? ExactSphere(oracle, c, piece.radius)
                        : ExactCapsule(oracle, c + Vec3(0, 0, -piece.half_length),
                                       c + Vec3(0, 0, piece.half_length), piece.radius);
    s.measured.push_back(got.distance);
    s.exact.push_back(e.distance);
    // The query's normal points from the link into the object: the exact outward normal, negated.
    s.angle_deg.push_back(std::acos(std::clamp(-got.normal_P.dot(e.normal), -1.0, 1.0)) * 180.0 /
                          M_PI);
    s.normal_checked.push_back(e.normal_defined);
  }
  return s;
}

// Where the depth and the normal must be exact: penetrating, or apart by up to 10 mm.
constexpr double kContactRange = 0.01;

// Returns {steps compared, normals checked}; `min_normal_share` of the compared steps must have a
// checkable normal.
std::array<int, 2> ExpectSweep(const Sweep& s, const std::string& what,
                               double min_normal_share = 0.5, double tolerance = 1e-3) {
  int normals = 0;
  int compared = 0;
  for (std::size_t k = 0; k < s.measured.size(); ++k) {
    if (s.exact[k] > kContactRange) {
      // Far away only needs to stay far away (the grid ends 25 mm outside the surface).
      EXPECT_GT(s.measured[k], 0.5 * kContactRange) << what << " step " << k;
      continue;
    }
    ++compared;
    EXPECT_NEAR(s.measured[k], s.exact[k], tolerance) << what << " step " << k;
    if (k > 0) {
      EXPECT_LE(s.measured[k], s.measured[k - 1] + 1e-5)
          << what << ": depth not monotonic at step " << k;
    }
    if (s.normal_checked[k]) {
      ++normals;
      EXPECT_LT(s.angle_deg[k], 10.0) << what << " step " << k;
    }
  }
  EXPECT_GE(compared, 3) << what;
  std::string table;
  for (std::size_t k = 0; k < s.measured.size(); ++k)
    table += "\n  step " + std::to_string(k) + ": " + std::to_string(s.measured[k] * 1e3) +
             " mm, exact " + std::to_string(s.exact[k] * 1e3) + " mm, normal off by " +
             std::to_string(s.angle_deg[k]) +
             (s.normal_checked[k] ? " deg" : " deg (near the medial axis)");
  EXPECT_GE(normals, std::max(1, static_cast<int>(min_normal_share * compared)))
      << what << ": too few steps away from the medial axis" << table;
  return {compared, normals};
}

// An octagonal prism (apothem 30 mm, half-height 40 mm), whole or cut by a grid of planes.
struct Prism {
  std::vector<Vec3> n;
  std::vector<double> d;
  Prism() {
    for (int i = 0; i < 8; ++i) {
      const double a = i * M_PI / 4.0 + 0.1;
      n.emplace_back(std::cos(a), std::sin(a), 0.0);
      d.push_back(0.03);
    }
    n.emplace_back(0, 0, 1), d.push_back(0.04);
    n.emplace_back(0, 0, -1), d.push_back(0.04);
  }

  // The prism cut into cuts^3 cells of its bounding box (cuts = 1: the whole prism; the special
  // value 0: two halves along x).
  std::vector<ConvexPiece> Pieces(int cuts) const {
    std::vector<std::array<double, 2>> bx, by, bz;
    auto ranges = [](int k, double half) {
      std::vector<std::array<double, 2>> r;
      for (int i = 0; i < k; ++i)
        r.push_back({-half + 2.0 * half * i / k, -half + 2.0 * half * (i + 1) / k});
      return r;
    };
    if (cuts == 0) {
      bx = {{-0.05, 0.004}, {0.004, 0.05}};
      by = ranges(1, 0.05);
      bz = ranges(1, 0.05);
    } else {
      bx = by = ranges(cuts, 0.033);
      bz = ranges(cuts, 0.04);
    }
    std::vector<ConvexPiece> pieces;
    for (const auto& rx : bx)
      for (const auto& ry : by)
        for (const auto& rz : bz) {
          std::vector<Vec3> pn = n;
          std::vector<double> pd = d;
          const std::array<std::array<double, 2>, 3> r = {rx, ry, rz};
          for (int a = 0; a < 3; ++a) {
            pn.push_back(Vec3::Unit(a)), pd.push_back(r[a][1]);
            pn.push_back(-Vec3::Unit(a)), pd.push_back(-r[a][0]);
          }
          // Vertices: every triple of planes meeting in a point inside all of them.
          std::vector<Vec3> vertices;
          for (std::size_t i = 0; i < pn.size(); ++i)
            for (std::size_t j = i + 1; j < pn.size(); ++j)
              for (std::size_t k = j + 1; k < pn.size(); ++k) {
                Mat3 M;
                M << pn[i].transpose(), pn[j].transpose(), pn[k].transpose();
                if (std::abs(M.determinant()) < 1e-9) continue;
                const Vec3 x = M.inverse() * Vec3(pd[i], pd[j], pd[k]);
                bool in = true;
                for (std::size_t f = 0; f < pn.size() && in; ++f)
                  in = pn[f].dot(x) <= pd[f] + 1e-12;
                if (in) vertices.push_back(x);
              }
          if (vertices.size() < 4) continue;
          try {
            pieces.push_back(ComputeConvexHull(vertices, "prism cell"));
          } catch (const InputError&) {
            // a cell that touches the prism in a face or an edge only
          }
        }
    return pieces;
  }
};

ObjectModel PrismObject(int cuts, const std::string& source, const std::string& cache,
                        double spacing = 1e-3) {
  ObjectModel o;
  o.name = "prism";
  o.pieces = Prism().Pieces(cuts);
  ContactFieldOptions options;
  options.source = source;
  options.cache_dir = cache;
  options.params.spacing = spacing;
  AttachContactField(o, options, "prism");
  return o;
}

// Fields are cached by content in the user's cache folder (as in use): each is built once per
// machine, by whichever test needs it first; only the cache test uses a folder of its own.
TEST(ContactField, SphereAndCapsuleIntoAConvexSolidWholeAndCut) {
  const std::vector<ConvexPiece> whole = Prism().Pieces(1);
  ASSERT_EQ(whole.size(), 1u);
  const TriangleMesh surface = whole[0].ToMesh();
  const MeshOracle oracle({&surface});
  const HandModel hand = ProbeHand(0.008);
  const Vec3 dir = Vec3(-1.0, -0.2, 0.1).normalized();
  struct Case {
    int cuts;
    std::string source;
    std::size_t pieces;
  };
  // One hull through GJK (no field) and through the field; then 2, 8 and 64 pieces.
  for (const Case& c : {Case{1, "none", 1}, Case{1, "pieces", 1}, Case{0, "auto", 2},
                        Case{2, "auto", 8}, Case{4, "auto", 64}}) {
    const ObjectModel object = PrismObject(c.cuts, c.source, "");
    EXPECT_EQ(object.pieces.size(), c.pieces);
    EXPECT_EQ(object.field != nullptr, c.source != "none");
    const std::string what = std::to_string(object.pieces.size()) + " piece(s), field " + c.source;
    // From 5 mm outside to 24 mm deep (medial axis beyond), off the cut planes and on them.
    for (const Vec3& offset : {Vec3(0, 0.0041, -0.0033), Vec3(0, 0, 0)}) {
      const Vec3 start = Vec3(0.051, 0.0, 0.0) + offset;
      ExpectSweep(Push(hand, object, oracle, "tip", start, dir, 0.0025, 12), what + ", sphere");
      ExpectSweep(Push(hand, object, oracle, "phalanx", start, dir, 0.0025, 10),
                  what + ", capsule");
    }
  }
}

TEST(ContactField, PerPieceDepthIsWhatTheFieldFixes) {
  // The failure the field exists for: 64 pieces, per-piece GJK stops at a piece's thickness.
  const HandModel hand = ProbeHand(0.008);
  const ObjectModel pieces = PrismObject(4, "none", "");
  const ObjectModel field = PrismObject(4, "auto", "");
  const std::vector<ConvexPiece> whole = Prism().Pieces(1);
  const TriangleMesh surface = whole[0].ToMesh();
  const MeshOracle oracle({&surface});
  const Sweep a =
      Push(hand, pieces, oracle, "tip", Vec3(0.03, 0.001, 0.002), Vec3(-1, 0, 0), 0.005, 5);
  const Sweep b =
      Push(hand, field, oracle, "tip", Vec3(0.03, 0.001, 0.002), Vec3(-1, 0, 0), 0.005, 5);
  double worst_pieces = 0.0, worst_field = 0.0;
  for (std::size_t k = 0; k < a.exact.size(); ++k) {
    worst_pieces = std::max(worst_pieces, std::abs(a.measured[k] - a.exact[k]));
    worst_field = std::max(worst_field, std::abs(b.measured[k] - b.exact[k]));
  }
  EXPECT_GT(worst_pieces, 0.01);  // per-piece: off by more than 10 mm
  EXPECT_LT(worst_field, 1e-3);
}

TEST(ContactField, CacheRoundTripsAndIsKeyedByGeometry) {
  test::TempDir cache;  // a 3 mm grid: the cache is under test here, not the accuracy
  const ObjectModel a = PrismObject(2, "auto", cache.path(), 3e-3);
  ASSERT_TRUE(a.field);
  ASSERT_TRUE(std::filesystem::exists(a.field_cache));
  const ObjectModel b = PrismObject(2, "auto", cache.path(), 3e-3);  // read back
  EXPECT_EQ(a.field_cache, b.field_cache);
  EXPECT_EQ(a.field->values, b.field->values);
  EXPECT_EQ(a.field->dims, b.field->dims);
  EXPECT_EQ(a.field->source, b.field->source);
  const ObjectModel c = PrismObject(4, "auto", cache.path(), 3e-3);  // other pieces, other file
  EXPECT_NE(a.field_cache, c.field_cache);
  // A truncated cache file is rebuilt, not trusted.
  std::filesystem::resize_file(a.field_cache, 100);
  const ObjectModel d = PrismObject(2, "auto", cache.path(), 3e-3);
  EXPECT_EQ(d.field->values, a.field->values);
}

TEST(ContactField, ObjectJsonSettingsAreReadAndChecked) {
  test::TempDir dir;
  fs::copy(test::ProjectAsset("objects/brush"), dir / "b", fs::copy_options::recursive);
  const std::string json = test::ReadFile(dir / "b/object.json");
  auto with = [&](const std::string& setting) {
    std::string text = json;
    const std::size_t at = text.find("\"contact_field\"");
    const std::size_t end = text.find('\n', at);
    text.replace(at, end - at, "\"contact_field\": " + setting + ",");
    std::ofstream(dir / "b/object.json") << text;
    return dir / "b/object.json";
  };
  const ObjectModel none = LoadObjectModel(with(R"({"source": "none"})"));
  EXPECT_FALSE(none.field);
  const ObjectModel coarse =
      LoadObjectModel(with(R"({"source": "visual", "spacing": 0.004, "padding": 0.01})"));
  ASSERT_TRUE(coarse.field);
  EXPECT_DOUBLE_EQ(coarse.field->spacing, 0.004);
  EXPECT_NE(coarse.field->source.find("closed mesh"), std::string::npos);
  for (const char* bad :
       {R"({"spacng": 0.001})", R"({"source": "sdf"})", R"({"spacing": -1})", R"("pieces")"}) {
    try {
      LoadObjectModel(with(bad));
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("contact_field"), std::string::npos) << e.what();
    }
  }
}

TEST(ContactField, BadParametersAreNamed) {
  ObjectModel o;
  o.pieces = Prism().Pieces(2);
  ContactFieldOptions options;
  options.source = "sdf";
  try {
    AttachContactField(o, options, "x.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'source' is 'sdf'"), std::string::npos) << e.what();
  }
  options.source = "auto";
  options.params.spacing = 0.0;
  EXPECT_THROW(AttachContactField(o, options, "x.json"), InputError);
  options.params.spacing = 1e-3;
  options.source = "visual";  // no visual mesh at all
  EXPECT_THROW(AttachContactField(o, options, "x.json"), InputError);
}

// The outline's point (issue 16): seen from 300 mm, a 10 mm cylinder's outline is the line where
// its normal is perpendicular to the line of sight, at cos φ = r / d about its axis, for every z;
// a box's, the edge past which the next face turns away.
TEST(ContactField, GrazingPointIsWhereTheLineOfSightLeavesTheSurface) {
  DistanceFieldParams params;
  params.spacing = 1e-3;
  const double r = 0.010, d = 0.300;
  const DistanceField cylinder = BuildDistanceFieldFromPieces(
      {ConvexPiece::Cylinder(r, 0.040, Transform::Identity())}, params);
  const Vec3 eye(d, 0.0, 0.0);
  const double phi = std::acos(r / d);
  const auto on = [](double radius, double angle, double z) {
    return Vec3(radius * std::cos(angle), radius * std::sin(angle), z);
  };
  for (const double offset : {0.0, 0.0004}) {  // on the field's surface, and 0.4 mm outside it
    const double radius = r + offset;
    const double grazing = std::acos(radius / d);
    for (const double sign : {1.0, -1.0}) {
      const Vec3 start = on(radius, sign * (phi - 30.0 * M_PI / 180), 0.005);
      const Vec3 g = GrazingPoint(cylinder, start, eye, 0.008);  // 30 deg of arc is 5.2 mm
      EXPECT_NEAR(std::hypot(g.x(), g.y()), radius, 5e-5) << offset;
      // Within the field's normals (central differences of a trilinear field, 1 mm grid: 1.2 deg
      // off here), 0.2 mm of arc, which the camera sees along its line of sight.
      EXPECT_NEAR(std::atan2(g.y(), g.x()), sign * grazing, 0.03) << offset << " " << sign;
      EXPECT_NEAR(g.z(), 0.005, 5e-4);
      const Vec3 n(std::cos(std::atan2(g.y(), g.x())), std::sin(std::atan2(g.y(), g.x())), 0.0);
      EXPECT_LT(std::abs(n.dot((g - eye).normalized())), 0.03);
      // A roll about the axis moves the grazing point along the line of sight, unlike the start.
      const Vec3 roll = Vec3::UnitZ().cross(g), roll_start = Vec3::UnitZ().cross(start);
      EXPECT_LT(roll.cross((g - eye).normalized()).norm(), 0.05 * r);
      EXPECT_GT(roll_start.cross((start - eye).normalized()).norm(), 0.45 * r);
    }
  }
  // Too far to walk, and a point the eye does not see: left where they are.
  const Vec3 far = on(r, phi - 30.0 * M_PI / 180, 0.0);
  EXPECT_EQ(GrazingPoint(cylinder, far, eye, 0.002), far);
  const Vec3 behind = on(r, phi + 20.0 * M_PI / 180, 0.0);
  EXPECT_EQ(GrazingPoint(cylinder, behind, eye, 0.008), behind);

  const DistanceField box = BuildDistanceFieldFromPieces(
      {ConvexPiece::Box(Vec3(0.02, 0.02, 0.02), Transform::Identity())}, params);
  const Vec3 face(0.02, 0.012, 0.003);  // on the +x face; the +y face turns away from the eye
  const Vec3 edge = GrazingPoint(box, face, eye, 0.020);
  // On the edge, within the field's rounding of it (about half a spacing); the walk followed the
  // line of sight's slope in z (3 mm over 12 mm): 2 mm up over the 8 mm to the edge.
  EXPECT_NEAR(edge.x(), 0.02, 6e-4);
  EXPECT_NEAR(edge.y(), 0.02, 6e-4);
  EXPECT_NEAR(edge.z(), 0.005, 5e-4);
}

// The YCB scans as a user loads them (visual scan + VHACD pieces): the field is the scan's
// closed surface. Sphere (an Allegro fingertip's radius) and capsule pushed towards the centre
// along three directions.
TEST(ContactField, YcbScansWithTheirVhacdPieces) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const HandModel hand = ProbeHand(0.014);
  int compared = 0, normals = 0;
  for (const char* name : {"mustard_bottle", "bleach_cleanser", "large_marker"}) {
    ContactFieldOptions options;
    const std::string file = test::SharedAssets() + "/objects/ycb/" + name + ".urdf";
    const ObjectModel object = LoadObjectModel(file, {}, options);
    ASSERT_TRUE(object.field) << name;
    EXPECT_GT(object.pieces.size(), 20u) << name;
    EXPECT_NE(object.field->source.find("closed mesh"), std::string::npos) << object.field->source;
    std::vector<const TriangleMesh*> visual;
    for (const TriangleMesh& m : object.visual) visual.push_back(&m);
    const MeshOracle oracle(visual);
    const Aabb box = object.Bounds();
    const Vec3 centre = box.Center();
    // From the side, as fingers grasp: across the longest axis of the bounding box, along the
    // two others and a diagonal between them.
    int longest = 0;
    box.Size().maxCoeff(&longest);
    const Vec3 u = Vec3::Unit((longest + 1) % 3), v = Vec3::Unit((longest + 2) % 3);
    for (const Vec3& raw : {u, Vec3(-v), Vec3(u + v + 0.2 * Vec3::Unit(longest))}) {
      const Vec3 dir = raw.normalized();
      // Start 5 mm outside the bounding box along -dir, stop at the centre.
      double reach = 0.0;
      for (int a = 0; a < 3; ++a) reach += std::abs(dir[a]) * 0.5 * box.Size()[a];
      const Vec3 start = centre + dir * (reach + 0.005 + 0.014);
      const int steps = static_cast<int>((reach + 0.019) / 0.004);
      const std::string what =
          std::string(name) + " along " + std::to_string(raw.x()) + "," + std::to_string(raw.y());
      // Monotonic only while approaching the medial axis: cut the sweep where the exact depth
      // stops growing.
      for (const char* link : {"tip", "phalanx"}) {
        Sweep s = Push(hand, object, oracle, link, start, -dir, 0.004, steps);
        std::size_t keep = 1;
        while (keep < s.exact.size() && s.exact[keep] <= s.exact[keep - 1]) ++keep;
        s.measured.resize(keep), s.exact.resize(keep), s.angle_deg.resize(keep),
            s.normal_checked.resize(keep);
        const std::array<int, 2> n = ExpectSweep(s, what + " " + link, 0.0);
        compared += n[0], normals += n[1];
      }
    }
  }
  // Thin objects (the marker's radius is 9 mm) have most of their inside near the medial axis;
  // over all sweeps, at least half of the steps have their normal checked.
  EXPECT_GE(normals, compared / 2);
  std::printf("YCB sweeps: %d steps compared, %d normals checked\n", compared, normals);
}

// The sweep reported in issue 15 (centre distances 25, 20, 15, 10, 0 mm of a 14 mm fingertip
// sphere from the object's centre), per-piece GJK beside the field and the exact depth.
TEST(ContactField, MustardSweepReport) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const HandModel hand = ProbeHand(0.014);
  const std::string file = test::SharedAssets() + "/objects/ycb/mustard_bottle.urdf";
  ContactFieldOptions none, field;
  none.source = "none";
  const ObjectModel per_piece = LoadObjectModel(file, {}, none);
  const ObjectModel whole = LoadObjectModel(file, {}, field);
  std::vector<const TriangleMesh*> visual;
  for (const TriangleMesh& m : whole.visual) visual.push_back(&m);
  const MeshOracle oracle(visual);
  const Vec3 centre = whole.Bounds().Center();
  const Vec3 dir(1, 0, 0);
  std::printf("centre distance [mm] | per-piece depth | field depth | exact depth [mm]\n");
  double prev = -1.0;
  for (double s : {0.025, 0.020, 0.015, 0.010, 0.0}) {
    const Sweep a = Push(hand, per_piece, oracle, "tip", centre + dir * s, dir, 0.0, 1);
    const Sweep b = Push(hand, whole, oracle, "tip", centre + dir * s, dir, 0.0, 1);
    std::printf("%5.0f | %6.1f | %6.1f | %6.1f\n", s * 1e3, -a.measured[0] * 1e3,
                -b.measured[0] * 1e3, -b.exact[0] * 1e3);
    EXPECT_NEAR(b.measured[0], b.exact[0], 1e-3);
    EXPECT_GT(-b.measured[0], prev);
    prev = -b.measured[0];
  }
}

}  // namespace
}  // namespace inhand
