// One full joint-rate step (predict + contact queries + update, torque contacts on) for the
// project's hand holding each of the five objects, and for the Allegro hand of
// ../shared/assets when present. Target (issue 3): median <= 1 ms per step.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

#include "bench_paths.hpp"
#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"

namespace inhand {
namespace {

struct FilterScene {
  HandModel hand;
  ObjectModel object;
  std::unique_ptr<BulletContactQuery> query;
  Eigen::VectorXd q;
  Eigen::VectorXd tau;  // a firm grip: 5 N into the object at every touching link
  Transform T_PO;
};

// A grasp-like state: joints 60 % of the way into their range from the middle, and the object
// moved from far above the palm towards it until at least three links are within 1 mm.
FilterScene MakeFilterScene(const std::string& urdf, const std::string& object_file,
                            const Mat3& R_PO) {
  FilterScene s;
  HandLoadOptions options;
  options.load_visual_meshes = false;
  s.hand = LoadHandModel(urdf, options);
  s.object = LoadObjectModel(object_file);
  s.query = std::make_unique<BulletContactQuery>(s.hand, s.object);
  s.q.resize(s.hand.num_q());
  for (int i = 0; i < s.hand.num_q(); ++i) {
    const Joint& j = s.hand.joints[s.hand.q_joints[i]];
    s.q[i] = j.lower + 0.65 * (j.upper - j.lower);
  }
  KinematicsData kin(s.hand);
  kin.Update(s.hand, s.q);
  Vec3 centroid = Vec3::Zero();
  int n = 0;
  for (std::size_t l = 0; l < s.hand.links.size(); ++l)
    if (!s.hand.links[l].collision.empty())
      centroid += kin.T_PL(static_cast<int>(l)).translation(), ++n;
  centroid /= n;
  // Approach along the direction from the root towards the links' centroid.
  const Vec3 dir = centroid.norm() > 1e-6 ? Vec3(centroid.normalized()) : Vec3::UnitZ();
  const Vec3 com_offset = R_PO * s.object.Bounds().Center();
  std::vector<ContactPair> pairs;
  for (double t = 0.3; t > -0.3; t -= 0.0005) {
    s.T_PO = MakeTransform(centroid + t * dir - com_offset, R_PO);
    s.query->Query(kin.link_poses(), s.T_PO, 0.001, pairs);
    if (pairs.size() >= 3) break;
  }
  s.tau = Eigen::VectorXd::Zero(s.hand.num_q());
  Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, s.hand.num_q());
  for (const ContactPair& p : pairs) {
    PointJacobian(s.hand, kin, p.link, p.c_f_P, J);
    s.tau += J.transpose() * (5.0 * p.normal_P);
  }
  return s;
}

void StepBenchmark(benchmark::State& state, const std::string& urdf, const std::string& object,
                   const Mat3& R) {
  if (!std::filesystem::exists(urdf)) {
    state.SkipWithError(("absent: " + urdf).c_str());
    return;
  }
  FilterScene s = MakeFilterScene(urdf, object, R);
  FilterParams params;
  Filter filter(s.hand, *s.query, params, FilterOptions{true});
  filter.Reset(s.T_PO, s.q, StartSigmas{0.02, 0.087, 0.087, {}});
  Eigen::VectorXd q = s.q;
  const Eigen::VectorXd& tau = s.tau;
  long k = 0, contacts = 0, constraints = 0;
  for (auto _ : state) {
    q.array() += (k++ % 2 ? -2e-4 : 2e-4);  // small finger motion, as at 1 kHz
    filter.Step(q, tau, 0.001);
    contacts += static_cast<long>(filter.trace().contacts.size());
    constraints += filter.trace().num_constraints;
    benchmark::DoNotOptimize(filter.position());
  }
  state.counters["contacts_per_step"] =
      benchmark::Counter(static_cast<double>(contacts) / std::max(k, 1L));
  state.counters["constraints_per_step"] =
      benchmark::Counter(static_cast<double>(constraints) / std::max(k, 1L));
}

const std::string kHand = kRoot + "/assets/hands/inhand_hand/inhand_hand.urdf";
const std::string kShared = kRoot + "/../shared/assets";
const Mat3 kAcross = ExpSO3(Vec3(0, M_PI / 2, 0));  // a bottle lying across the palm

void BM_Step_InhandHand_Ketchup(benchmark::State& s) {
  StepBenchmark(s, kHand, kRoot + "/assets/objects/ketchup_bottle/object.json", kAcross);
}
void BM_Step_InhandHand_Brush(benchmark::State& s) {
  StepBenchmark(s, kHand, kRoot + "/assets/objects/brush/object.json", Mat3::Identity());
}
void BM_Step_InhandHand_Water(benchmark::State& s) {
  StepBenchmark(s, kHand, kRoot + "/assets/objects/water_bottle/object.json", kAcross);
}
void BM_Step_InhandHand_Shampoo(benchmark::State& s) {
  StepBenchmark(s, kHand, kRoot + "/assets/objects/shampoo_bottle/object.json", kAcross);
}
void BM_Step_InhandHand_Pen(benchmark::State& s) {
  StepBenchmark(s, kHand, kRoot + "/assets/objects/pen/object.json", Mat3::Identity());
}
void BM_Step_Allegro_Ketchup(benchmark::State& s) {
  StepBenchmark(s, kShared + "/hands/allegro_hand/allegro_hand_right.urdf",
                kRoot + "/assets/objects/ketchup_bottle/object.json", kAcross);
}
void BM_Step_Allegro_YcbMustard(benchmark::State& s) {
  StepBenchmark(s, kShared + "/hands/allegro_hand/allegro_hand_right.urdf",
                kShared + "/objects/ycb/mustard_bottle.urdf", Mat3::Identity());
}

BENCHMARK(BM_Step_InhandHand_Ketchup)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Step_InhandHand_Brush)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Step_InhandHand_Water)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Step_InhandHand_Shampoo)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Step_InhandHand_Pen)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Step_Allegro_Ketchup)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Step_Allegro_YcbMustard)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace inhand
