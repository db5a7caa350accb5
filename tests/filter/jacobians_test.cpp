// The filter's Jacobians against finite differences: the grasp map, the twist from contacts, the
// contact and visual measurements, the camera pose, the pose error.
#include <gtest/gtest.h>

#include "fixtures.hpp"
#include "inhand/filter/contact_model.hpp"
#include "inhand/filter/filter.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

using filter_test::CameraLookingAt;
using filter_test::TestIntrinsics;

TEST(FilterJacobians, GraspMapBlockIsTheObjectPointVelocity) {
  const Vec3 p(0.01, 0.05, 0.03), c(0.03, 0.02, 0.06);
  Vec6 nu;
  nu << 0.1, -0.2, 0.05, 0.7, -0.3, 1.1;
  const double h = 1e-7;
  const auto point = [&](double t) {
    return Vec3(p + nu.head<3>() * t + ExpSO3(nu.tail<3>() * t) * (c - p));
  };
  const Vec3 fd = (point(h) - point(-h)) / (2 * h);
  EXPECT_LT((GraspMapBlock(c, p) * nu - fd).norm(), 1e-8);
}

TEST(FilterJacobians, TwistFromContactsIncludingDegenerateCases) {
  Vec6 nu;
  nu << 0.02, -0.01, 0.03, 0.4, 0.2, -0.5;
  const Vec3 p(0.0, 0.05, 0.04);
  const auto velocity = [&](const Vec3& c) { return Vec3(GraspMapBlock(c, p) * nu); };
  // Three non-collinear contacts: the twist is determined and recovered.
  TwistSolver full;
  for (const Vec3& c : {Vec3(0.03, 0.05, 0.04), Vec3(-0.03, 0.06, 0.04), Vec3(0.0, 0.05, 0.08)})
    full.Add(GraspMapBlock(c, p), velocity(c));
  EXPECT_LT((full.Solve(1e-12) - nu).norm(), 1e-6);
  // One contact, and collinear contacts: under-determined; the solver returns the minimum-norm
  // twist that reproduces the contact velocities, as the pseudo-inverse does.
  for (const std::vector<Vec3>& cs :
       {std::vector<Vec3>{Vec3(0.03, 0.05, 0.04)},
        std::vector<Vec3>{Vec3(0.03, 0.05, 0.04), Vec3(0.06, 0.05, 0.04),
                          Vec3(-0.02, 0.05, 0.04)}}) {
    TwistSolver solver;
    Eigen::MatrixXd A(3 * cs.size(), 6);
    Eigen::VectorXd b(3 * cs.size());
    for (std::size_t i = 0; i < cs.size(); ++i) {
      solver.Add(GraspMapBlock(cs[i], p), velocity(cs[i]));
      A.block<3, 6>(3 * i, 0) = GraspMapBlock(cs[i], p);
      b.segment<3>(3 * i) = velocity(cs[i]);
    }
    const Vec6 got = solver.Solve(1e-12);
    const Vec6 pinv = A.completeOrthogonalDecomposition().solve(b);
    EXPECT_LT((A * got - b).norm(), 1e-7);
    EXPECT_LT((got - pinv).norm(), 1e-5) << got.transpose() << "\n" << pinv.transpose();
  }
}

// Nearly collinear contacts (one 0.2 mm off the line, as pinching fingertips are): the rotation
// about that line is barely determined, and undamped, 20 µm of measurement noise turns into
// degrees of rotation in one step. The default damping keeps the step a translation.
TEST(FilterJacobians, DefaultTwistDampingKeepsNoiseOutOfIllConditionedRotations) {
  const Vec3 p(0.0, 0.05, 0.04);
  const Vec3 shift(0.0, 0.0, 0.001);  // the fingers move the object 1 mm
  const std::vector<Vec3> contacts{Vec3(-0.02, 0.05, 0.04), Vec3(0.0, 0.05, 0.0402),
                                   Vec3(0.02, 0.05, 0.04)};
  const std::vector<Vec3> noise{Vec3(2e-5, -1e-5, 2e-5), Vec3(-1e-5, 2e-5, -2e-5),
                                Vec3(1e-5, 1e-5, 2e-5)};
  TwistSolver solver;
  for (std::size_t i = 0; i < contacts.size(); ++i)
    solver.Add(GraspMapBlock(contacts[i], p), shift + noise[i]);
  const Vec6 undamped = solver.Solve(1e-8);
  const Vec6 damped = solver.Solve(FilterParams().twist_damping);
  EXPECT_GT(undamped.tail<3>().norm(), 2.0 * M_PI / 180);
  EXPECT_LT(damped.tail<3>().norm(), 0.3 * M_PI / 180);
  EXPECT_LT((damped.head<3>() - shift).norm(), 0.2 * shift.norm());
}

TEST(FilterJacobians, ContactMeasurementJacobianMatchesFiniteDifferences) {
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  const int m = hand.num_q(), n = 6 + m;
  const int link = hand.LinkIndex("index_distal");
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(m, 0.3);
  const Vec3 x_f(0.002, 0.015, 0.009);  // fixed on the link
  const Vec3 x_o(0.01, -0.02, 0.05);    // fixed on the object
  for (const Mat3& R : {Mat3(Mat3::Identity()), ExpSO3(Vec3(0.3, -1.1, 0.4)),
                        ExpSO3(Vec3(M_PI, 0, 0)), ExpSO3(M_PI * Vec3(1, 1, 0).normalized())}) {
    const Vec3 p(0.01, 0.07, 0.03);
    KinematicsData kin(hand);
    const auto h = [&](const Eigen::VectorXd& d) {
      kin.Update(hand, q + d.tail(m));
      const Vec3 c_f = kin.T_PL(link) * x_f;
      const Vec3 c_o = p + d.head<3>() + ExpSO3(d.segment<3>(3)) * R * x_o;
      return Vec3(c_f - c_o);
    };
    kin.Update(hand, q);
    Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, m), H(3, n);
    PointJacobian(hand, kin, link, kin.T_PL(link) * x_f, J);
    ContactMeasurementJacobian(Vec3(p + R * x_o), p, J, H);
    Eigen::Matrix<double, 3, Eigen::Dynamic> N(3, n);
    for (int i = 0; i < n; ++i) {
      Eigen::VectorXd a = Eigen::VectorXd::Zero(n), b = a;
      a[i] = 1e-6;
      b[i] = -1e-6;
      N.col(i) = (h(a) - h(b)) / 2e-6;
    }
    EXPECT_LT((H - N).cwiseAbs().maxCoeff(), 1e-7) << "R=\n" << R << "\nH=\n" << H << "\nN=\n" << N;
  }
}

// ∂pix/∂e at e = 0 by central differences, pix: 6-vector -> pixel.
template <typename Pixel>
Eigen::Matrix<double, 2, 6> CentralDifferences(const Pixel& pix) {
  Eigen::Matrix<double, 2, 6> N;
  for (int i = 0; i < 6; ++i) {
    Vec6 a = Vec6::Zero(), b = Vec6::Zero();
    a[i] = 1e-7;
    b[i] = -1e-7;
    N.col(i) = (pix(a) - pix(b)) / 2e-7;
  }
  return N;
}

TEST(FilterJacobians, VisualJacobianMatchesFiniteDifferences) {
  const Intrinsics K = TestIntrinsics();
  const Vec3 p(0.0, 0.06, 0.04);
  const Transform T_PC = CameraLookingAt(p);
  for (const Mat3& R :
       {Mat3(Mat3::Identity()), ExpSO3(Vec3(M_PI, 0, 0)), ExpSO3(Vec3(0.2, 0.5, -0.7))}) {
    for (const Vec3& x_o : {Vec3(0.0, 0.0, 0.0), Vec3(0.03, -0.02, 0.1), Vec3(-0.2, 0.1, 0.05)}) {
      const auto pix = [&](const Vec6& d) {
        const Vec3 X = p + d.head<3>() + ExpSO3(d.tail<3>()) * R * x_o;
        return K.Project(T_PC.inverse() * X);
      };
      const Vec3 X = p + R * x_o;
      ASSERT_GT((T_PC.inverse() * X).z(), 0.0);
      const auto H = VisualMeasurementJacobian(X, p, T_PC, K);
      const Eigen::Matrix<double, 2, 6> N = CentralDifferences(pix);
      EXPECT_LT((H - N).cwiseAbs().maxCoeff(), 1e-4 * std::max(1.0, H.cwiseAbs().maxCoeff()))
          << H << "\n"
          << N;
    }
  }
}

TEST(FilterJacobians, CameraPoseJacobianMatchesFiniteDifferences) {
  const Intrinsics K = TestIntrinsics();
  const Transform T_PC = CameraLookingAt(Vec3(0.0, 0.06, 0.04));
  for (const Vec3& X : {Vec3(0.0, 0.06, 0.04), Vec3(0.03, 0.04, 0.14), Vec3(-0.1, 0.1, 0.0)}) {
    const auto pix = [&](const Vec6& e) {
      return K.Project((T_PC * MakeTransform(e.head<3>(), ExpSO3(e.tail<3>()))).inverse() * X);
    };
    const auto C = CameraPoseJacobian(X, T_PC, K);
    const Eigen::Matrix<double, 2, 6> N = CentralDifferences(pix);
    EXPECT_LT((C - N).cwiseAbs().maxCoeff(), 1e-4 * std::max(1.0, C.cwiseAbs().maxCoeff()))
        << C << "\n"
        << N;
  }
}

// PoseError(a, b) is the error state that takes b to a: a = (p_b + δp, Exp(δθ) R_b).
TEST(FilterJacobians, PoseErrorIsTheErrorStateBetweenTwoPoses) {
  const Transform b = MakeTransform(Vec3(0.01, -0.02, 0.05), ExpSO3(Vec3(0.4, -1.2, 2.0)));
  for (const Vec6& d :
       {Vec6((Vec6() << 0.003, -0.01, 0.02, 0.1, -0.3, 0.2).finished()), Vec6(Vec6::Zero()),
        Vec6((Vec6() << 0.0, 0.0, 0.0, 0.0, 3.0, 0.0).finished())}) {
    const Transform a =
        MakeTransform(b.translation() + d.head<3>(), ExpSO3(d.tail<3>()) * b.linear());
    EXPECT_LT((PoseError(a, b) - d).norm(), 1e-12) << d.transpose();
  }
}

}  // namespace
}  // namespace inhand
