// One classification of a triangle's shape for every narrow-phase path (triangle_class.hpp):
// the thresholds, and a needle classified the same by the sphere, box and triangle-distance
// routines (before, a triangle of relative height between 64 ulps of double and 1e-10 was a face
// to the sphere and capsule paths and triangle distance but a segment to the box path).

#include <crux/geometry/box_triangle_contact.hpp>
#include <crux/geometry/contact.hpp>
#include <crux/geometry/triangle_class.hpp>
#include <crux/geometry/triangle_contact.hpp>
#include <crux/geometry/triangle_distance.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace crux {
namespace {

TEST(TriangleClass, RelativeHeightDrawsTheLines) {
  EXPECT_TRUE(classifyTriangle(0, 1).degenerate);
  EXPECT_TRUE(classifyTriangle(kTriangleDegenerateRelative, 1).degenerate);  // on the line: degenerate
  EXPECT_TRUE(classifyTriangle(std::numeric_limits<double>::quiet_NaN(), 1).degenerate);
  const TriangleClass needle = classifyTriangle(2 * kTriangleDegenerateRelative, 1);
  EXPECT_FALSE(needle.degenerate);
  EXPECT_TRUE(needle.thin);
  EXPECT_EQ(needle.referenceFace, 2 * kTriangleDegenerateRelative >= kTriangleFaceRelative);
  EXPECT_FALSE(classifyTriangle(2 * kTriangleThinRelative, 1).thin);
  const TriangleClass proper = classifyTriangle(1, 1);  // height = longest edge / 1 (doubled area)
  EXPECT_FALSE(proper.degenerate);
  EXPECT_FALSE(proper.thin);
  EXPECT_TRUE(proper.referenceFace);
  // the reference-face line lies above the degenerate one (float builds: ~1.4e-10; double: ~0.075)
  EXPECT_GT(kTriangleFaceRelative, kTriangleDegenerateRelative);
  EXPECT_FALSE(classifyTriangle(0.5 * kTriangleFaceRelative, 1).referenceFace);
  EXPECT_TRUE(classifyTriangle(2 * kTriangleFaceRelative, 1).referenceFace);
}

/// The needle (0,0,0), (8,0,0), (4, 8h, 0): relative height h.
Triangle needle(double h) { return Triangle{Vec3(0, 0, 0), Vec3(8, 0, 0), Vec3(4, Real(8 * h), 0)}; }

bool isFace(std::uint32_t feature) { return (feature >> 24) == std::uint32_t(FeatureKind::Face); }

TEST(TriangleClass, ANeedleIsTheSameToTheSphereBoxAndDistancePaths) {
  for (const double h : {1e-12, 5e-11, 1e-9, 1e-6}) {
    const Triangle t = needle(h);
    const bool degenerate = h <= kTriangleDegenerateRelative;
    SCOPED_TRACE("relative height " + std::to_string(h));
    // a sphere resting on the needle's middle from above
    SphereTriangleContact s;
    ASSERT_TRUE(sphereTriangleContact(t, Vec3(4, 0, Real(0.5)), Real(0.5), 0, s));
    EXPECT_EQ(s.region == SphereTriangleContact::kDegenerate, degenerate);
    // a box (half 1, centred at the origin) resting on the needle moved to its bottom face
    Triangle below = t;
    for (Vec3* p : {&below.a, &below.b, &below.c}) *p += Vec3(-4, 0, -1);
    ContactManifold box;
    ASSERT_TRUE(boxTriangleContacts(Vec3(1, 1, 1), below, 0, box));
    bool boxFace = false;
    for (int i = 0; i < box.count; ++i) boxFace = boxFace || isFace(box.points[i].featureA);
    if (degenerate) EXPECT_FALSE(boxFace);  // no normal axis: its edges and corners only
    // the closest points of a triangle above the needle's middle, on the needle
    const Triangle above{Vec3(4, -1, 1), Vec3(4, 1, 1), Vec3(4, 0, 2)};
    const TriangleDistanceResult d = closestPoints(t, above);
    EXPECT_NEAR(double(d.distance), 1, 1e-6);
    if (degenerate) EXPECT_FALSE(isFace(d.featureA)) << d.featureA;
  }
}

TEST(TriangleClass, AThinTriangleIsNeverTheReferenceFaceOfABoxContact) {
  // Relative height between the degenerate and the reference-face lines, in either precision: a
  // triangle with a face and a normal axis, too thin to be a manifold's reference face. Pressed
  // 0.01 into the bottom face of a box (half 1, at the origin), parallel to it, so the triangle's
  // normal and the box face tie as the axis: the box face is the reference in the box routine,
  // as in contacts() (before, the box routine clipped the box against the thin triangle).
  const double h = std::sqrt(kTriangleDegenerateRelative * kTriangleFaceRelative);
  const TriangleClass shape = classifyTriangle(h, 1);
  ASSERT_FALSE(shape.degenerate);
  ASSERT_FALSE(shape.referenceFace);
  Triangle below = needle(h);
  for (Vec3* p : {&below.a, &below.b, &below.c}) *p += Vec3(-4, 0, Real(-0.99));
  const std::uint32_t bottomFace = featureId(FeatureKind::Face, 4);  // the box's −z face
  ContactManifold box, generic;
  ASSERT_TRUE(boxTriangleContacts(Vec3(1, 1, 1), below, 0, box));
  ASSERT_TRUE(contacts(ConvexShape(below), Transform{}, ConvexShape(Obb{Vec3::Zero(), Vec3(1, 1, 1), Mat3::Identity()}),
                       Transform{}, 0, generic));
  for (const ContactManifold* m : {&box, &generic}) {
    SCOPED_TRACE(m == &box ? "boxTriangleContacts" : "contacts");
    EXPECT_EQ(m->normal, Vec3(0, 0, -1));
    ASSERT_GE(m->count, 2);
    for (int i = 0; i < m->count; ++i) {
      const ContactPoint& c = m->points[i];
      EXPECT_EQ(c.featureB, bottomFace) << i;
      EXPECT_EQ(c.pointB.z(), -1) << i;                                     // on the box face
      EXPECT_LE(std::abs(double(c.pointA.x())), 1) << i;                    // within it
      EXPECT_NEAR(double(c.separation), -(double(c.pointA.z()) + 1), 1e-12) << i;  // exactly its depth below it
      EXPECT_NEAR(double(c.separation), -(double(Real(-0.99)) + 1), 1e-6) << i;
    }
  }
}

}  // namespace
}  // namespace crux
