// Tests of src/geometry/shapes.cpp: validate() accepts valid shapes (degenerate ones included)
// and rejects each broken precondition with an InvalidInput naming the field.

#include <gtest/gtest.h>

#include <cmath>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/shapes.hpp>
#include <crux/precondition.hpp>
#include <limits>
#include <string>

namespace crux {
namespace {

constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
constexpr Real kInf = std::numeric_limits<Real>::infinity();

/// Success iff f throws InvalidInput whose message contains `part`.
template <class F>
::testing::AssertionResult throwsNaming(F&& f, const std::string& part) {
  try {
    f();
  } catch (const InvalidInput& e) {
    const std::string message = e.what();
    if (message.find(part) != std::string::npos) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "message \"" << message << "\" does not name \"" << part << "\"";
  }
  return ::testing::AssertionFailure() << "no InvalidInput thrown (expected one naming \"" << part << "\")";
}

TEST(ValidateShapes, ValidShapesPass) {
  EXPECT_NO_THROW(validate(Ray{Vec3(1, 2, 3), Vec3(0, 0, -1)}));
  EXPECT_NO_THROW(validate(Segment{Vec3(1, 2, 3), Vec3(1, 2, 3)}));  // a point
  EXPECT_NO_THROW(validate(Sphere{Vec3(0, 0, 0), 0}));               // a point
  EXPECT_NO_THROW(validate(Aabb{Vec3(0, 0, 0), Vec3(1, 0, 2)}));     // flat
  EXPECT_NO_THROW(validate(Obb{Vec3(1, 1, 1), Vec3(0, 0, 0), Mat3::Identity()}));
  Mat3 permuted;
  permuted << 0, -1, 0, 0, 0, 1, 1, 0, 0;  // signed permutation, left-handed is fine
  EXPECT_NO_THROW(validate(Obb{Vec3(0, 0, 0), Vec3(1, 2, 3), permuted}));
  const Mat3 rotation = Quat(Eigen::AngleAxis<Real>(Real(0.7), Vec3(1, 2, 3).normalized())).toRotationMatrix();
  EXPECT_NO_THROW(validate(Obb{Vec3(0, 0, 0), Vec3(1, 2, 3), rotation}));
  EXPECT_NO_THROW(validate(Plane{Vec3(0, 0, 5), -2}));                               // non-unit normal
  EXPECT_NO_THROW(validate(Triangle{Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2)}));  // collinear
  EXPECT_NO_THROW(validate(Triangle{Vec3(3, 3, 3), Vec3(3, 3, 3), Vec3(3, 3, 3)}));  // a point
  EXPECT_NO_THROW(validatePoint(Vec3(-1, 0, 1e30f)));
}

TEST(ValidateShapes, NonFiniteCoordinatesNameTheField) {
  EXPECT_TRUE(throwsNaming([] { validate(Ray{Vec3(kNaN, 0, 0), Vec3(1, 0, 0)}); }, "ray.origin"));
  EXPECT_TRUE(throwsNaming([] { validate(Ray{Vec3(0, 0, 0), Vec3(0, kInf, 0)}); }, "ray.dir"));
  EXPECT_TRUE(throwsNaming([] { validate(Segment{Vec3(0, 0, 0), Vec3(0, 0, -kInf)}); }, "segment.end"));
  EXPECT_TRUE(throwsNaming([] { validate(Segment{Vec3(kNaN, 0, 0), Vec3(0, 0, 0)}); }, "segment.start"));
  EXPECT_TRUE(throwsNaming([] { validate(Sphere{Vec3(0, kNaN, 0), 1}); }, "sphere.center"));
  EXPECT_TRUE(throwsNaming([] { validate(Sphere{Vec3(0, 0, 0), kInf}); }, "sphere.radius"));
  EXPECT_TRUE(throwsNaming([] { validate(Aabb{Vec3(kNaN, 0, 0), Vec3(1, 1, 1)}); }, "aabb.min"));
  EXPECT_TRUE(throwsNaming([] { validate(Aabb{Vec3(0, 0, 0), Vec3(1, kInf, 1)}); }, "aabb.max"));
  EXPECT_TRUE(throwsNaming([] { validate(Obb{Vec3(0, 0, kNaN), Vec3(1, 1, 1), Mat3::Identity()}); }, "obb.center"));
  EXPECT_TRUE(throwsNaming([] { validate(Obb{Vec3(0, 0, 0), Vec3(1, kNaN, 1), Mat3::Identity()}); }, "obb.half"));
  EXPECT_TRUE(throwsNaming(
      [] {
        Mat3 axes = Mat3::Identity();
        axes(1, 2) = kNaN;
        validate(Obb{Vec3(0, 0, 0), Vec3(1, 1, 1), axes});
      },
      "obb.axes[2]"));
  EXPECT_TRUE(throwsNaming([] { validate(Plane{Vec3(0, kInf, 1), 0}); }, "plane.normal"));
  EXPECT_TRUE(throwsNaming([] { validate(Plane{Vec3(0, 0, 1), kNaN}); }, "plane.d"));
  EXPECT_TRUE(throwsNaming([] { validate(Triangle{Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(kNaN, 0, 0)}); }, "triangle[2]"));
  EXPECT_TRUE(throwsNaming([] { validatePoint(Vec3(0, -kInf, 0), "query"); }, "query"));
}

TEST(ValidateShapes, CallerChosenNameIsUsed) {
  EXPECT_TRUE(throwsNaming([] { validate(Sphere{Vec3(0, 0, 0), -1}, "b"); }, "b.radius"));
}

TEST(ValidateShapes, ZeroRayDirection) {
  EXPECT_TRUE(throwsNaming([] { validate(Ray{Vec3(1, 2, 3), Vec3(0, 0, 0)}); }, "ray.dir"));
}

TEST(ValidateShapes, NegativeRadius) {
  EXPECT_TRUE(throwsNaming([] { validate(Sphere{Vec3(0, 0, 0), Real(-0.5)}); }, "sphere.radius is negative"));
}

TEST(ValidateShapes, MinGreaterThanMaxNamesTheAxis) {
  EXPECT_TRUE(throwsNaming([] { validate(Aabb{Vec3(0, 2, 0), Vec3(1, 1, 1)}); }, "aabb.min.y"));
  EXPECT_TRUE(throwsNaming([] { validate(Aabb{Vec3(0, 0, 1), Vec3(1, 1, 0)}); }, "aabb.min.z"));
  // The empty box is not a valid query shape.
  EXPECT_TRUE(throwsNaming([] { validate(Aabb::empty()); }, "aabb"));
}

TEST(ValidateShapes, NegativeObbHalfExtent) {
  EXPECT_TRUE(throwsNaming([] { validate(Obb{Vec3(0, 0, 0), Vec3(1, -1, 1), Mat3::Identity()}); }, "obb.half"));
}

TEST(ValidateShapes, NonOrthonormalObbAxes) {
  EXPECT_TRUE(throwsNaming(
      [] {
        Mat3 a = Mat3::Identity();
        a(0, 0) = 2;  // a non-unit axis
        validate(Obb{Vec3(0, 0, 0), Vec3(1, 1, 1), a});
      },
      "obb.axes"));
  EXPECT_TRUE(throwsNaming(
      [] {
        Mat3 sheared = Mat3::Identity();
        sheared(0, 1) = Real(0.1);  // axes not orthogonal
        validate(Obb{Vec3(0, 0, 0), Vec3(1, 1, 1), sheared});
      },
      "orthonormal"));
  EXPECT_TRUE(throwsNaming([] { validate(Obb{Vec3(0, 0, 0), Vec3(1, 1, 1), Mat3::Zero()}); }, "obb.axes"));
  // Just beyond the documented tolerance is rejected, well inside it is accepted.
  Mat3 nearly = Mat3::Identity();
  nearly(2, 2) = 1 + 4 * kObbOrthonormalityTolerance;
  EXPECT_THROW(validate(Obb{Vec3(0, 0, 0), Vec3(1, 1, 1), nearly}), InvalidInput);
  nearly(2, 2) = 1 + kObbOrthonormalityTolerance / 4;
  EXPECT_NO_THROW(validate(Obb{Vec3(0, 0, 0), Vec3(1, 1, 1), nearly}));
}

TEST(ValidateShapes, ZeroPlaneNormal) {
  EXPECT_TRUE(throwsNaming([] { validate(Plane{Vec3(0, 0, 0), 1}); }, "plane.normal"));
}


// Found by fuzz_geometry: a plane whose normal is non-zero but whose squared length underflows
// (possible for double Reals; float normals square exactly in Wide) passed validate, and every
// distance to it divides by |normal|², giving Inf/NaN. validate now rejects it; a tiny normal
// whose square is representable still gives finite answers.
TEST(ValidateShapes, PlaneNormalWhoseSquaredLengthUnderflows) {
  const Real tiny = std::numeric_limits<Real>::denorm_min();
  const Plane plane{Vec3(tiny, tiny, 0), 0};
  if (Wide(tiny) * Wide(tiny) == 0) {
    EXPECT_TRUE(throwsNaming([&] { validate(plane); }, "plane.normal"));
  } else {
    validate(plane);
    const Vec3 p(3, -5, 7);
    const Vec3 q = closestPoint(plane, p);
    EXPECT_TRUE(q.allFinite()) << q.transpose();
    EXPECT_EQ(q.z(), Real(7));
    EXPECT_TRUE(std::isfinite(squaredDistance(plane, p)));
  }
}

// ---- queryable: the cheap preconditions, without throwing ----------------------------------------

/// Every kind of bad input the queries may be handed, with what validate() says of it.
TEST(Queryable, RefusesWhatValidateRefusesOnTheCheapRules) {
  const Real nan = std::numeric_limits<Real>::quiet_NaN(), inf = std::numeric_limits<Real>::infinity();
  const auto both = [](const auto& shape) {
    bool threw = false;
    try {
      validate(shape);
    } catch (const InvalidInput&) {
      threw = true;
    }
    return std::pair<bool, bool>{queryable(shape), threw};
  };
  for (const Real bad : {nan, inf, -inf}) {
    for (int i = 0; i < 3; ++i) {
      Vec3 v = Vec3(1, 2, 3);
      v[i] = bad;
      EXPECT_EQ(both(Ray{v, Vec3(0, 0, 1)}), std::make_pair(false, true));
      EXPECT_EQ(both(Ray{Vec3::Zero(), v}), std::make_pair(false, true));
      EXPECT_EQ(both(Segment{v, Vec3::Zero()}), std::make_pair(false, true));
      EXPECT_EQ(both(Segment{Vec3::Zero(), v}), std::make_pair(false, true));
      EXPECT_EQ(both(Sphere{v, 1}), std::make_pair(false, true));
      EXPECT_EQ(both(Aabb{v, Vec3::Constant(9)}), std::make_pair(false, true));
      EXPECT_EQ(both(Obb{v, Vec3::Ones(), Mat3::Identity()}), std::make_pair(false, true));
      EXPECT_EQ(both(Plane{v, 0}), std::make_pair(false, true));
      EXPECT_EQ(both(Triangle{v, Vec3::Zero(), Vec3::Ones()}), std::make_pair(false, true));
      EXPECT_FALSE(queryable(v));
    }
    EXPECT_EQ(both(Sphere{Vec3::Zero(), bad}), std::make_pair(false, true));
    EXPECT_EQ(both(Plane{Vec3(0, 0, 1), bad}), std::make_pair(false, true));
  }
  EXPECT_EQ(both(Ray{Vec3::Zero(), Vec3::Zero()}), std::make_pair(false, true));
  EXPECT_EQ(both(Sphere{Vec3::Zero(), -1}), std::make_pair(false, true));
  EXPECT_EQ(both(Aabb{Vec3(1, 0, 0), Vec3(0, 1, 1)}), std::make_pair(false, true));
  EXPECT_EQ(both(Obb{Vec3::Zero(), Vec3(1, -1, 1), Mat3::Identity()}), std::make_pair(false, true));
  EXPECT_EQ(both(Plane{Vec3::Zero(), 0}), std::make_pair(false, true));
  // valid, degenerate included: queryable and no exception
  EXPECT_EQ(both(Ray{Vec3::Zero(), Vec3(0, 0, 1e-3f)}), std::make_pair(true, false));
  EXPECT_EQ(both(Sphere{Vec3::Zero(), 0}), std::make_pair(true, false));
  EXPECT_EQ(both(Aabb{Vec3::Zero(), Vec3::Zero()}), std::make_pair(true, false));
  EXPECT_EQ(both(Obb{Vec3::Zero(), Vec3::Zero(), Mat3::Identity()}), std::make_pair(true, false));
  EXPECT_EQ(both(Triangle{Vec3::Zero(), Vec3::Zero(), Vec3::Zero()}), std::make_pair(true, false));
  EXPECT_EQ(both(Segment{Vec3::Ones(), Vec3::Ones()}), std::make_pair(true, false));
  // The rule is a squared norm > 0 in Wide: a subnormal direction passes when Wide is wider than
  // Real (float builds: its square is a normal double) and is refused when they are the same
  // (double builds: its square underflows to 0).
  EXPECT_EQ(queryable(Ray{Vec3::Zero(), Vec3(0, std::numeric_limits<Real>::denorm_min(), 0)}),
            sizeof(Wide) > sizeof(Real));
}

TEST(Precondition, AViolationAbortsNamingTheQueryAndTheRule) {
  EXPECT_DEATH(detail::preconditionFailed("raycastClosest(Mesh, Ray)", "a finite ray"),
               "crux: precondition violated in raycastClosest\\(Mesh, Ray\\): a finite ray");
}

}  // namespace
}  // namespace crux
