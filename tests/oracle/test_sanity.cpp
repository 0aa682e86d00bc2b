// The oracle sanity suite: a fixed set of UNAMBIGUOUS cases — clear separation or clear
// penetration, gaps and depths of at least 5% of the operands' size (near cases: 1.5-2%, still
// five times above every backend's declared error) — that every built backend must answer
// exactly as designed for every op it supports. A backend that fails here is misconfigured (a margin left on, a quaternion read in
// the wrong order, a half-space taken for a plane, a culling convention flipped), and none of its
// disagreements in the differential fuzzer can be believed until it passes.
//
// Each case is designed in a canonical frame where its answer is evident (stated next to it);
// the suite runs it in four frames (scale 1 at and away from the origin, 0.01, 100), on every
// backend whose declared working range (WorldTolerance::minFeature, absolute) covers the frame. Booleans
// must match exactly; distances, points and normals within 4 × the backend's declared tolerance
// plus the rounding of the inputs to Real. Ops a backend does not support must throw Unsupported
// with the protocol's message. Also here: the world factory (makeWorld) and the exception
// boundary.

#include <crux/geometry/convex.hpp>
#include <crux/world/collision_world.hpp>
#include <crux/world/native_world.hpp>
#include <world_factory.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>
#include "support/printing.hpp"

namespace crux {
namespace {

using test_support::str;

// ---------------------------------------------------------------------------------------------
// The frame a case runs in: canonical coordinates x map to scale·x + offset.

struct Frame {
  double scale = 1;
  Vec3d offset = Vec3d::Zero();

  Vec3 p(double x, double y, double z) const { return (scale * Vec3d(x, y, z) + offset).cast<Real>(); }
  Vec3 v(double x, double y, double z) const { return (scale * Vec3d(x, y, z)).cast<Real>(); }
  Real len(double l) const { return Real(scale * l); }
  Vec3d expectP(double x, double y, double z) const { return scale * Vec3d(x, y, z) + offset; }
  /// Magnitude of the case's coordinates (for tolerances).
  double magnitude() const { return scale * 8 + offset.cwiseAbs().maxCoeff(); }
  /// The smallest shape extent of the cases (the bar's thickness, a box's 0.2-unit slab).
  double smallestFeature() const { return scale * 0.2; }
  /// The smallest designed gap or depth (5% of the operands' size).
  double smallestGap() const { return scale * 0.05; }
  /// Whether the frame lies in a backend's working range: shapes above its minimum feature and
  /// gaps ten times above its error.
  bool within(const WorldTolerance& t) const {
    return smallestFeature() >= t.minFeature && smallestGap() >= 10 * t.at(magnitude());
  }
  std::string name() const { return "scale " + str(scale) + " offset " + str(offset); }
};

/// The canonical triangle of the primitive cases: the right triangle (0,0,0), (4,0,0), (0,4,0) in
/// the plane z = 0 (hypotenuse x + y = 4).
Triangle canonicalTriangle(const Frame& f) { return {f.p(0, 0, 0), f.p(4, 0, 0), f.p(0, 4, 0)}; }

/// A box mesh (12 triangles, counter-clockwise seen from outside) with the given centre and half
/// extents.
std::shared_ptr<const Mesh> boxMesh(const Vec3& c, const Vec3& h, const std::string& name) {
  std::vector<Vec3> v;
  for (int k = 0; k < 8; ++k)
    v.push_back(c + Vec3((k & 1) ? h.x() : -h.x(), (k & 2) ? h.y() : -h.y(), (k & 4) ? h.z() : -h.z()));
  // Faces as quads of corner indices; orientation fixed below from the outward direction.
  const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  std::vector<TriangleIndices> t;
  for (const auto& q : quads) {
    const Vec3 faceCenter = (v[q[0]] + v[q[1]] + v[q[2]] + v[q[3]]) / 4;
    const Vec3 n = (v[q[1]] - v[q[0]]).cross(v[q[2]] - v[q[0]]);
    const bool outward = n.dot(faceCenter - c) > 0;
    const auto a = std::uint32_t(q[0]), b = std::uint32_t(q[1]), cc = std::uint32_t(q[2]), d = std::uint32_t(q[3]);
    if (outward) {
      t.push_back({a, b, cc});
      t.push_back({a, cc, d});
    } else {
      t.push_back({a, cc, b});
      t.push_back({a, d, cc});
    }
  }
  return std::make_shared<const Mesh>(std::move(v), std::move(t), name);
}

/// An open grid in the plane z = 0 over [-4, 4]² of 8 × 8 unit cells, two triangles each,
/// counter-clockwise seen from +z.
std::shared_ptr<const Mesh> gridMesh(const Frame& f) {
  std::vector<Vec3> v;
  for (int j = 0; j <= 8; ++j)
    for (int i = 0; i <= 8; ++i) v.push_back(f.p(i - 4, j - 4, 0));
  std::vector<TriangleIndices> t;
  for (std::uint32_t j = 0; j < 8; ++j)
    for (std::uint32_t i = 0; i < 8; ++i) {
      const std::uint32_t a = j * 9 + i, b = a + 1, c = a + 10, d = a + 9;
      t.push_back({a, b, c});
      t.push_back({a, c, d});
    }
  return std::make_shared<const Mesh>(std::move(v), std::move(t), "grid");
}

// ---------------------------------------------------------------------------------------------
// Cases.

/// What a case asks and what it must answer.
struct Answer {
  bool hit = false;
  std::optional<Vec3d> point;   ///< closest point, or ray hit point
  std::optional<double> t;      ///< ray distance
  std::optional<Vec3d> normal;  ///< ray hit normal
  std::vector<double> allT;     ///< every hit distance (All rays)
  std::vector<std::string> names;  ///< model names (children, scene_query, scene_pairs as "a|b", ray hit model)
};

struct Case {
  std::string name;
  WorldOp op;
  std::function<Answer(CollisionWorld&)> run;
  Answer expected;
  /// The case's smallest gap or depth in canonical units. Near cases (0.015 - 0.02) sit below
  /// Bullet's default margins (0.04 for convex shapes such as btTriangleShape, 0.01 per GImpact
  /// shape) but far above every backend's declared error: they catch a margin left on.
  double gap = 0.05;
};

Answer hitAnswer(bool hit) {
  Answer a;
  a.hit = hit;
  return a;
}

Answer rayAnswer(const std::optional<WorldRayHit>& h) {
  Answer a;
  a.hit = h.has_value();
  if (h) {
    a.t = h->t;
    a.point = h->point;
    a.normal = h->normal;
  }
  return a;
}

/// The meshes every world of the suite holds, per frame: "cube" = [-1,1]³, "grid" (above); and,
/// centred at the origin for mesh_mesh (placed by transforms): "cube0" = [-1,1]³, "small0" =
/// [-0.3,0.3]³, "bar0" = [-3,3]×[-0.1,0.1]×[-0.1,0.1].
void addMeshes(CollisionWorld& w, const Frame& f) {
  w.addMesh("cube", boxMesh(f.p(0, 0, 0), f.v(1, 1, 1), "cube"));
  w.addMesh("grid", gridMesh(f));
  w.addMesh("cube0", boxMesh(Vec3::Zero(), f.v(1, 1, 1), "cube0"));
  w.addMesh("small0", boxMesh(Vec3::Zero(), f.v(0.3, 0.3, 0.3), "small0"));
  w.addMesh("bar0", boxMesh(Vec3::Zero(), f.v(3, 0.1, 0.1), "bar0"));
}

/// A rotation of `degrees` about a unit axis.
Quat rotationAbout(const Vec3d& axis, double degrees) {
  const double half = degrees * 3.14159265358979323846 / 360;
  const Vec3d a = axis.normalized() * std::sin(half);
  return Quat(Real(std::cos(half)), Real(a.x()), Real(a.y()), Real(a.z()));
}

Obb obb(const Vec3& center, const Vec3& half, const Quat& rotation) {
  Obb b;
  b.center = center;
  b.half = half;
  b.axes = rotation.toRotationMatrix();
  return b;
}

std::vector<Case> primitiveCases(const Frame& f) {
  std::vector<Case> cs;
  const Triangle T = canonicalTriangle(f);
  auto closest = [&](const std::string& name, Vec3 p, Vec3d expect) {
    Answer e;
    e.hit = true;
    e.point = expect;
    cs.push_back({name, WorldOp::ClosestPointTriangle,
                  [T, p](CollisionWorld& w) {
                    Answer a;
                    a.hit = true;
                    a.point = w.closestPoint(T, p);
                    return a;
                  },
                  e});
  };
  closest("point above the face projects onto it", f.p(1, 1, 2), f.expectP(1, 1, 0));
  closest("point in a vertex region gives the vertex", f.p(6, -1, 1), f.expectP(4, 0, 0));
  closest("point in an edge region gives the edge point", f.p(2, -3, 0.5), f.expectP(2, 0, 0));
  closest("point beyond the hypotenuse gives its foot", f.p(3, 3, -1), f.expectP(2, 2, 0));

  auto boolean = [&](const std::string& name, WorldOp op, bool expect, std::function<bool(CollisionWorld&)> q,
                     double gap = 0.05) {
    cs.push_back({name, op, [q](CollisionWorld& w) { return hitAnswer(q(w)); }, hitAnswer(expect), gap});
  };
  auto sphere = [&](const std::string& name, Vec3 c, double r, bool expect) {
    const Sphere s{c, f.len(r)};
    boolean(name, WorldOp::TriangleSphere, expect, [T, s](CollisionWorld& w) { return w.overlaps(T, s); });
  };
  sphere("sphere 2 above the face, r 1: apart", f.p(1, 1, 2), 1, false);
  sphere("sphere 2 above the face, r 2.5: crossing", f.p(1, 1, 2), 2.5, true);
  sphere("sphere 2.45 from a vertex, r 1.5: apart", f.p(6, -1, 1), 1.5, false);
  sphere("sphere 2.45 from a vertex, r 3: crossing", f.p(6, -1, 1), 3, true);
  sphere("sphere centred on the face", f.p(1, 1, 0), 0.5, true);

  auto aabb = [&](const std::string& name, Vec3 lo, Vec3 hi, bool expect) {
    const Aabb b{lo, hi};
    boolean(name, WorldOp::TriangleAabb, expect, [T, b](CollisionWorld& w) { return w.overlaps(T, b); });
  };
  aabb("box pierced by the face", f.p(0.5, 0.5, -1), f.p(1.5, 1.5, 1), true);
  aabb("box 1.41 beyond the hypotenuse", f.p(3, 3, -1), f.p(4, 4, 1), false);
  aabb("box 0.5 above the face", f.p(1, 1, 0.5), f.p(2, 2, 1.5), false);
  aabb("box containing the triangle", f.p(-10, -10, -10), f.p(10, 10, 10), true);
  boolean("box 0.02 above the face (near)", WorldOp::TriangleAabb, false,
          [T, b = Aabb{f.p(1, 1, 0.02), f.p(2, 2, 1)}](CollisionWorld& w) { return w.overlaps(T, b); }, 0.02);

  auto obbCase = [&](const std::string& name, const Obb& b, bool expect) {
    boolean(name, WorldOp::TriangleObb, expect, [T, b](CollisionWorld& w) { return w.overlaps(T, b); });
  };
  const Quat z45 = rotationAbout(Vec3d::UnitZ(), 45), x30 = rotationAbout(Vec3d::UnitX(), 30);
  obbCase("box turned 45 degrees, 0.21 beyond the hypotenuse", obb(f.p(2.5, 2.5, 0), f.v(0.5, 0.5, 0.5), z45), false);
  obbCase("box turned 45 degrees, centred on the hypotenuse", obb(f.p(2, 2, 0), f.v(0.5, 0.5, 0.5), z45), true);
  obbCase("box tilted 30 degrees, 0.22 above the face", obb(f.p(1, 1, 0.9), f.v(0.5, 0.5, 0.5), x30), false);
  obbCase("box tilted 30 degrees, through the face", obb(f.p(1, 1, 0.4), f.v(0.5, 0.5, 0.5), x30), true);
  // Left-handed axes are valid (the box is the same point set); peers that turn poses into
  // quaternions must not be handed a reflection.
  auto leftHanded = [](Obb b) {
    b.axes.col(2) = -b.axes.col(2);
    return b;
  };
  obbCase("left-handed box, tilted 30 degrees, 0.22 above the face",
          leftHanded(obb(f.p(1, 1, 0.9), f.v(0.5, 0.5, 0.5), x30)), false);
  obbCase("left-handed box, tilted 30 degrees, through the face",
          leftHanded(obb(f.p(1, 1, 0.4), f.v(0.5, 0.5, 0.5), x30)), true);
  // A long box turned 90 degrees about z (its long local x axis along world y), left-handed:
  // read with any other orientation it would give the opposite answer.
  const Quat z90 = rotationAbout(Vec3d::UnitZ(), 90);
  obbCase("left-handed long box along y reaching into the triangle",
          leftHanded(obb(f.p(1, -2.5, 0), f.v(3, 0.2, 0.2), z90)), true);
  obbCase("left-handed long box along y beside the triangle",
          leftHanded(obb(f.p(-2.5, 1, 0), f.v(3, 0.2, 0.2), z90)), false);

  auto plane = [&](const std::string& name, Vec3d n, double d, bool expect) {
    // The plane n·x = d in canonical coordinates, moved by the frame: n·(x - o)/s = d.
    const Plane p{n.cast<Real>(), Real(f.scale * d + n.dot(f.offset))};
    boolean(name, WorldOp::TrianglePlane, expect, [T, p](CollisionWorld& w) { return w.overlaps(T, p); });
  };
  plane("plane z = 1 above the triangle", Vec3d(0, 0, 1), 1, false);
  plane("plane x + y = 2 across the triangle", Vec3d(1, 1, 0), 2, true);
  plane("plane 2x + 2y = 4 (non-unit normal) across the triangle", Vec3d(2, 2, 0), 4, true);
  plane("plane x = 5: the whole triangle below it", Vec3d(1, 0, 0), 5, false);
  plane("plane x = -1: the whole triangle above it", Vec3d(1, 0, 0), -1, false);

  auto tri = [&](const std::string& name, Triangle b, bool expect) {
    boolean(name, WorldOp::TriangleTriangle, expect, [T, b](CollisionWorld& w) { return w.overlaps(T, b); });
  };
  tri("upright triangle piercing the face", {f.p(1, 0.5, -1), f.p(1, 0.5, 1), f.p(1, 2.5, 0)}, true);
  tri("upright triangle 1 above the face", {f.p(1, 0.5, 1), f.p(1, 0.5, 3), f.p(1, 2.5, 2)}, false);
  tri("upright triangle beyond the hypotenuse", {f.p(3, 3, -1), f.p(3, 3, 1), f.p(5, 5, 0)}, false);
  tri("triangle in y = 1 crossing the face", {f.p(-1, 1, 1), f.p(3, 1, 1), f.p(1, 1, -2)}, true);
  boolean("upright triangle 0.02 above the face (near)", WorldOp::TriangleTriangle, false,
          [T, b = Triangle{f.p(1, 0.5, 0.02), f.p(1, 0.5, 2), f.p(1, 2.5, 1)}](CollisionWorld& w) {
            return w.overlaps(T, b);
          },
          0.02);

  auto ray = [&](const std::string& name, Vec3 o, Vec3 d, std::optional<double> t, Vec3d hitPoint, Vec3d normal) {
    const Ray r{o, d};
    Answer e;
    e.hit = t.has_value();
    if (t) {
      e.t = f.scale * *t;
      e.point = hitPoint;
      e.normal = normal;
    }
    cs.push_back({name, WorldOp::RayTriangle, [T, r](CollisionWorld& w) { return rayAnswer(w.raycast(r, T)); }, e});
  };
  ray("ray down onto the front face", f.p(1, 1, 5), f.v(0, 0, -1), 5, f.expectP(1, 1, 0), Vec3d(0, 0, 1));
  ray("ray up onto the back face", f.p(1, 1, -3), f.v(0, 0, 2), 3, f.expectP(1, 1, 0), Vec3d(0, 0, -1));
  ray("ray pointing away", f.p(1, 1, 5), f.v(0, 0, 1), std::nullopt, {}, {});
  ray("ray beside the hypotenuse", f.p(5, 5, 5), f.v(0, 0, -1), std::nullopt, {}, {});
  ray("slanted ray with a non-unit direction", f.p(-2, -1, 4), f.v(3, 2, -4), std::sqrt(29.0), f.expectP(1, 1, 0),
      Vec3d(0, 0, 1));

  auto segment = [&](const std::string& name, Vec3 a, Vec3 b, bool expect) {
    const Segment s{a, b};
    boolean(name, WorldOp::SegmentTriangle, expect, [T, s](CollisionWorld& w) { return w.intersects(s, T); });
  };
  segment("segment through the face", f.p(1, 1, 1), f.p(1, 1, -1), true);
  segment("segment ending 0.5 above the face", f.p(1, 1, 1), f.p(1, 1, 0.5), false);
  segment("segment beside the hypotenuse", f.p(5, 5, 1), f.p(5, 5, -1), false);
  segment("slanted segment through the face", f.p(-1, 2, -1), f.p(2, 1, 1), true);
  return cs;
}

std::vector<Case> meshCases(const Frame& f) {
  std::vector<Case> cs;
  auto boolean = [&](const std::string& name, WorldOp op, bool expect, std::function<bool(CollisionWorld&)> q,
                     double gap = 0.05) {
    cs.push_back({name, op, [q](CollisionWorld& w) { return hitAnswer(q(w)); }, hitAnswer(expect), gap});
  };
  const auto cube = [](CollisionWorld& w) { return w.meshHandle("cube"); };
  const auto grid = [](CollisionWorld& w) { return w.meshHandle("grid"); };

  // Rays. Closest hits report t, point and the normal facing the origin.
  auto ray = [&](const std::string& name, std::function<MeshHandle(CollisionWorld&)> mesh, Ray r,
                 RayQueryOptions options, RayCollect mode, Answer expect) {
    cs.push_back({name, WorldOp::MeshRay,
                  [mesh, r, options, mode](CollisionWorld& w) {
                    RayHitCollector hits(mode);
                    w.raycast(mesh(w), r, hits, options);
                    Answer a;
                    a.hit = hits.hasHit();
                    if (mode == RayCollect::Closest && hits.hit()) a = rayAnswer(hits.hit());
                    if (mode == RayCollect::All)
                      for (const WorldRayHit& h : hits.hits()) a.allT.push_back(h.t);
                    return a;
                  },
                  expect});
  };
  auto closestHit = [&](double t, Vec3d point, Vec3d normal) {
    Answer a;
    a.hit = true;
    a.t = f.scale * t;
    a.point = point;
    a.normal = normal;
    return a;
  };
  RayQueryOptions none;
  RayQueryOptions max3;
  max3.maxDistance = f.len(3);
  RayQueryOptions cull;
  cull.cullBackFaces = true;
  ray("ray down onto the cube's top face", cube, {f.p(0.2, 0.3, 5), f.v(0, 0, -1)}, none, RayCollect::Closest,
      closestHit(4, f.expectP(0.2, 0.3, 1), Vec3d(0, 0, 1)));
  ray("ray from inside the cube down to its bottom face", cube, {f.p(0.2, 0.3, 0.1), f.v(0, 0, -1)}, none,
      RayCollect::Closest, closestHit(1.1, f.expectP(0.2, 0.3, -1), Vec3d(0, 0, 1)));
  ray("ray along +x onto the cube's -x face", cube, {f.p(-5, 0.4, -0.3), f.v(2, 0, 0)}, none, RayCollect::Closest,
      closestHit(4, f.expectP(-1, 0.4, -0.3), Vec3d(-1, 0, 0)));
  ray("ray beside the cube", cube, {f.p(2, 2, 5), f.v(0, 0, -1)}, none, RayCollect::Closest, hitAnswer(false));
  ray("ray stopped by max distance 3 before the cube at 4", cube, {f.p(0.2, 0.3, 5), f.v(0, 0, -1)}, max3,
      RayCollect::Closest, hitAnswer(false));
  ray("any-hit ray through the cube", cube, {f.p(0.2, 0.3, 5), f.v(0, 0, -1)}, none, RayCollect::Any, hitAnswer(true));
  ray("any-hit ray beside the cube", cube, {f.p(2, 2, 5), f.v(0, 0, -1)}, none, RayCollect::Any, hitAnswer(false));
  {
    Answer both = hitAnswer(true);
    both.allT = {f.scale * 4, f.scale * 6};
    ray("all hits of a ray through the cube: top and bottom", cube, {f.p(0.2, 0.3, 5), f.v(0, 0, -1)}, none,
        RayCollect::All, both);
  }
  ray("culling keeps the front face hit from outside", cube, {f.p(0.2, 0.3, 5), f.v(0, 0, -1)}, cull,
      RayCollect::Closest, closestHit(4, f.expectP(0.2, 0.3, 1), Vec3d(0, 0, 1)));
  ray("culling drops the back face seen from inside", cube, {f.p(0.2, 0.3, 0.1), f.v(0, 0, -1)}, cull,
      RayCollect::Closest, hitAnswer(false));
  ray("ray down onto the grid inside a cell", grid, {f.p(0.3, 0.2, 5), f.v(0, 0, -1)}, none, RayCollect::Closest,
      closestHit(5, f.expectP(0.3, 0.2, 0), Vec3d(0, 0, 1)));
  ray("slanted ray up onto the grid's back", grid, {f.p(-2.6, 1.7, -2), f.v(1, -1, 1)}, none, RayCollect::Closest,
      closestHit(2 * std::sqrt(3.0), f.expectP(-0.6, -0.3, 0), Vec3d(0, 0, -1)));

  auto segment = [&](const std::string& name, Vec3 a, Vec3 b, bool expect) {
    const Segment s{a, b};
    boolean(name, WorldOp::MeshSegment, expect, [cube, s](CollisionWorld& w) { return w.intersects(cube(w), s); });
  };
  segment("segment through the cube's top face", f.p(0.2, 0.3, 2), f.p(0.2, 0.3, 0.5), true);
  segment("segment inside the cube (surface test)", f.p(0.1, 0.1, 0.1), f.p(0.2, 0.2, 0.2), false);
  segment("segment outside the cube", f.p(2, 2, 2), f.p(3, 3, 3), false);

  auto sphere = [&](const std::string& name, Vec3 c, double r, bool expect) {
    const Sphere s{c, f.len(r)};
    boolean(name, WorldOp::MeshSphere, expect, [cube, s](CollisionWorld& w) { return w.overlaps(cube(w), s); });
  };
  sphere("sphere 0.5 above the cube", f.p(0, 0, 2.5), 1, false);
  sphere("sphere crossing the cube's top", f.p(0, 0, 2.5), 2, true);
  sphere("sphere inside the cube (surface test)", f.p(0, 0, 0), 0.5, false);
  sphere("sphere crossing every face", f.p(0, 0, 0), 1.5, true);
  boolean("sphere 0.02 off the cube's top (near)", WorldOp::MeshSphere, false,
          [cube, s = Sphere{f.p(0, 0, 2.02), f.len(1)}](CollisionWorld& w) { return w.overlaps(cube(w), s); }, 0.02);

  auto aabb = [&](const std::string& name, Vec3 lo, Vec3 hi, bool expect) {
    const Aabb b{lo, hi};
    boolean(name, WorldOp::MeshAabb, expect, [cube, b](CollisionWorld& w) { return w.overlaps(cube(w), b); });
  };
  aabb("box 0.5 off the cube's corner", f.p(1.5, 1.5, 1.5), f.p(2, 2, 2), false);
  aabb("box over the cube's corner", f.p(0.5, 0.5, 0.5), f.p(2, 2, 2), true);
  aabb("box inside the cube (surface test)", f.p(-0.5, -0.5, -0.5), f.p(0.5, 0.5, 0.5), false);
  aabb("solid box around the whole cube", f.p(-2, -2, -2), f.p(2, 2, 2), true);

  auto obbCase = [&](const std::string& name, const Obb& b, bool expect) {
    boolean(name, WorldOp::MeshObb, expect, [cube, b](CollisionWorld& w) { return w.overlaps(cube(w), b); });
  };
  const Quat z45 = rotationAbout(Vec3d::UnitZ(), 45);
  obbCase("box turned 45 degrees, 0.49 off the cube", obb(f.p(2.2, 0, 0), f.v(0.5, 0.5, 0.5), z45), false);
  obbCase("box turned 45 degrees, into the cube", obb(f.p(1.5, 0, 0), f.v(0.5, 0.5, 0.5), z45), true);

  auto plane = [&](const std::string& name, Vec3d n, double d, bool expect) {
    const Plane p{n.cast<Real>(), Real(f.scale * d + n.dot(f.offset))};
    boolean(name, WorldOp::MeshPlane, expect, [cube, p](CollisionWorld& w) { return w.overlaps(cube(w), p); });
  };
  plane("plane z = 0.5 through the cube", Vec3d(0, 0, 1), 0.5, true);
  plane("plane z = 1.5 above the cube", Vec3d(0, 0, 1), 1.5, false);
  plane("plane x + y + z = 2.9 cutting a corner", Vec3d(1, 1, 1), 2.9, true);
  plane("plane x + y + z = 3.3 past the corner", Vec3d(1, 1, 1), 3.3, false);

  auto tri = [&](const std::string& name, Triangle t, bool expect) {
    boolean(name, WorldOp::MeshTriangle, expect, [cube, t](CollisionWorld& w) { return w.overlaps(cube(w), t); });
  };
  tri("large triangle slicing the cube", {f.p(-3, -3, 0), f.p(3, -3, 0), f.p(0, 3, 0)}, true);
  tri("small triangle inside the cube (surface test)", {f.p(-0.3, -0.3, 0), f.p(0.3, -0.3, 0), f.p(0, 0.3, 0)},
      false);
  tri("large triangle 2 above the cube", {f.p(-3, -3, 3), f.p(3, -3, 3), f.p(0, 3, 3)}, false);
  boolean("large triangle 0.02 above the cube (near)", WorldOp::MeshTriangle, false,
          [cube, t = Triangle{f.p(-3, -3, 1.02), f.p(3, -3, 1.02), f.p(0, 3, 1.02)}](CollisionWorld& w) {
            return w.overlaps(cube(w), t);
          },
          0.02);

  // mesh_mesh: meshes centred at the origin, placed by transforms (translation in the frame).
  auto place = [&](double x, double y, double z, const Quat& q = Quat::Identity()) {
    Transform t;
    t.rotation = q;
    t.translation = f.p(x, y, z);
    return t;
  };
  auto pair = [&](const std::string& name, std::string a, Transform ta, std::string b, Transform tb, bool expect,
                  double gap = 0.05) {
    boolean(
        name, WorldOp::MeshMesh, expect,
        [a, ta, b, tb](CollisionWorld& w) { return w.overlaps(w.meshHandle(a), ta, w.meshHandle(b), tb); }, gap);
  };
  const Quat plus30 = rotationAbout(Vec3d::UnitZ(), 30), minus30 = rotationAbout(Vec3d::UnitZ(), -30);
  const Quat tilt = rotationAbout(Vec3d(1, 2, 3), 40);
  pair("cubes overlapping by 0.5", "cube0", place(0, 0, 0), "cube0", place(1.5, 0.3, 0.2), true);
  pair("cubes 0.5 apart", "cube0", place(0, 0, 0), "cube0", place(2.5, 0, 0), false);
  pair("cubes 0.015 apart (near)", "cube0", place(0, 0, 0), "cube0", place(2.015, 0.1, -0.2), false, 0.015);
  pair("small cube inside the big one (surface test)", "cube0", place(0, 0, 0), "small0", place(0.1, 0.2, 0), false);
  pair("cube turned 45 degrees, 0.19 apart", "cube0", place(0, 0, 0), "cube0", place(2.6, 0, 0, z45), false);
  pair("cube turned 45 degrees, 0.21 deep", "cube0", place(0, 0, 0), "cube0", place(2.2, 0, 0, z45), true);
  // The bar's +x end goes to (2.60, 1.5) turned +30 degrees, to (2.60, -1.5) turned -30: only one
  // sign of rotation (and translation applied after rotation) reaches the small cube there.
  pair("bar turned +30 degrees ends inside a small cube", "bar0", place(0, 1, 0, plus30), "small0",
       place(2.598, 2.5, 0), true);
  pair("bar turned -30 degrees misses that small cube", "bar0", place(0, 1, 0, minus30), "small0",
       place(2.598, 2.5, 0), false);
  pair("both meshes turned about a slanted axis, overlapping", "cube0", place(0, 0, 0, tilt), "cube0",
       place(0.8, -0.6, 1.0, tilt), true);
  // Same rotation, offset 5 along x: in the cubes' frame some coordinate of the offset is at
  // least 5/sqrt(3) = 2.89 > 2, so they are at least 0.89 apart.
  pair("both meshes turned about a slanted axis, apart", "cube0", place(0, 0, 0, tilt), "cube0",
       place(5, 0, 0, tilt), false);
  return cs;
}

/// Narrow-phase and volume cases: signed distances (t = the distance; points are not
/// compared: closest points of FCL's GJK are within its tolerance only in the distance, see
/// docs/batch.md), contacts (t = deepest depth, normal from B to A), point_inside and volume-mode
/// booleans. Each distance has unique closest points and a gap of at least 0.25 (canonical).
std::vector<Case> narrowPhaseCases(const Frame& f) {
  std::vector<Case> cs;
  const auto cube = [](CollisionWorld& w) { return w.meshHandle("cube"); };
  auto place = [&](double x, double y, double z, const Quat& q = Quat::Identity()) {
    Transform t;
    t.rotation = q;
    t.translation = f.p(x, y, z);
    return t;
  };
  auto valued = [&](double t) {
    Answer a;
    a.hit = true;
    a.t = f.scale * t;
    return a;
  };
  // distance: the cube (A, world coordinates) against a convex shape (B), or two convex shapes.
  auto meshDistance = [&](const std::string& name, OperandShape shape, double expect) {
    cs.push_back({name, WorldOp::Distance,
                  [cube, shape](CollisionWorld& w) {
                    Answer a;
                    a.hit = true;
                    a.t = w.distance({cube(w), Transform{}}, {shape, Transform{}}).distance;
                    return a;
                  },
                  valued(expect), 0.25});
  };
  meshDistance("sphere r 0.5 centred 2 above the cube's top face: 0.5 apart", Sphere{f.p(0.2, 0.3, 2), f.len(0.5)},
               0.5);
  meshDistance("capsule along x, r 0.5, axis 2 above the cube: 0.5 apart",
               Capsule{f.p(-0.5, 0.1, 2), f.p(0.5, 0.1, 2), f.len(0.5)}, 0.5);
  meshDistance("unit box 3 beside the cube's +x face: 1 apart", obb(f.p(3, 0.2, -0.1), f.v(1, 1, 1), Quat::Identity()),
               1);
  auto convexDistance = [&](const std::string& name, OperandShape a, OperandShape b, double expect) {
    cs.push_back({name, WorldOp::Distance,
                  [a, b](CollisionWorld& w) {
                    Answer r;
                    r.hit = true;
                    r.t = w.distance({a, Transform{}}, {b, Transform{}}).distance;
                    return r;
                  },
                  valued(expect), 0.25});
  };
  convexDistance("unit box and a sphere r 1 centred 3 along x: 1 apart", obb(f.p(0, 0, 0), f.v(1, 1, 1), Quat::Identity()),
                 Sphere{f.p(3, 0, 0), f.len(1)}, 1);
  convexDistance("unit box and a sphere r 0.5 sunk 0.25 into its top face: -0.25",
                 obb(f.p(0, 0, 0), f.v(1, 1, 1), Quat::Identity()), Sphere{f.p(0.1, -0.2, 1.25), f.len(0.5)}, -0.25);
  convexDistance("tetrahedron's vertex 2 from a unit sphere",
                 ConvexHull::build({f.p(3, 0, 0), f.p(4, 0, 0), f.p(3, 1, 0), f.p(3, 0, 1)}),
                 Sphere{f.p(0, 0, 0), f.len(1)}, 2);
  // mesh_distance: cube0 ([-1,1]^3) and small0 ([-0.3,0.3]^3) placed by transforms.
  auto pairDistance = [&](const std::string& name, Transform ta, Transform tb, std::optional<double> expect,
                          double max = std::numeric_limits<double>::infinity()) {
    Answer e = expect ? valued(*expect) : Answer{};
    cs.push_back({name, WorldOp::MeshDistance,
                  [ta, tb, max](CollisionWorld& w) {
                    Answer a;
                    const auto d = w.meshDistance(w.meshHandle("cube0"), ta, w.meshHandle("small0"), tb, max);
                    a.hit = d.has_value();
                    if (d) a.t = d->distance;
                    return a;
                  },
                  e, 0.25});
  };
  pairDistance("small cube 2 along x from the cube: 0.7 apart", place(0, 0, 0), place(2, 0.1, -0.2), 0.7);
  pairDistance("small cube turned 45 degrees about z, 2.5 along x: 1.5 - 0.42 apart", place(0, 0, 0),
               place(2.5, 0, 0, rotationAbout(Vec3d::UnitZ(), 45)), 1.5 - 0.3 * std::sqrt(2.0));
  pairDistance("small cube 0.7 away, max 0.35: nothing within", place(0, 0, 0), place(2, 0.1, -0.2), std::nullopt,
               f.scale * 0.35);
  // contacts: a sphere r 0.5 sunk 0.25 into the cube's top face (deepest point).
  {
    Answer e = valued(0.25);
    e.normal = Vec3d(0, 0, -1);
    const Sphere s{f.p(0.2, 0.3, 1.25), f.len(0.5)};
    cs.push_back({"sphere sunk 0.25 into the cube's top: deepest contact 0.25, normal down", WorldOp::Contacts,
                  [cube, s](CollisionWorld& w) {
                    // The deepest point (Bullet reports a point per touching triangle; crux
                    // reduces them and drops the ghost contact of the top face's diagonal).
                    const std::vector<WorldContact> c = w.contacts({cube(w), Transform{}}, {s, Transform{}});
                    Answer a;
                    a.hit = !c.empty();
                    if (!c.empty()) {
                      const WorldContact& deepest = *std::max_element(
                          c.begin(), c.end(), [](const WorldContact& x, const WorldContact& y) { return x.depth < y.depth; });
                      a.t = deepest.depth;
                      a.normal = deepest.normal;
                    }
                    return a;
                  },
                  e, 0.25});
    cs.push_back({"sphere 0.5 above the cube: no contact", WorldOp::Contacts,
                  [cube, s2 = Sphere{f.p(0.2, 0.3, 2), f.len(0.5)}](CollisionWorld& w) {
                    return hitAnswer(!w.contacts({cube(w), Transform{}}, {s2, Transform{}}).empty());
                  },
                  hitAnswer(false), 0.5});
  }
  // point_inside and volume mode on the closed cube [-1,1]^3.
  auto inside = [&](const std::string& name, Vec3 p, bool expect) {
    cs.push_back({name, WorldOp::PointInside, [cube, p](CollisionWorld& w) { return hitAnswer(w.pointInside(cube(w), p)); },
                  hitAnswer(expect)});
  };
  inside("point in the cube", f.p(0.2, -0.3, 0.4), true);
  inside("point near a corner inside", f.p(0.9, 0.9, -0.9), true);
  inside("point beside the cube", f.p(1.5, 0.2, 0.1), false);
  inside("point far away on a diagonal", f.p(5, 5, 5), false);
  auto volume = [&](const std::string& name, WorldOp op, bool expect, std::function<bool(CollisionWorld&)> q) {
    cs.push_back({name, op, [q](CollisionWorld& w) { return hitAnswer(q(w)); }, hitAnswer(expect)});
  };
  volume("volume: small sphere wholly inside the cube", WorldOp::MeshSphereVolume, true,
         [cube, s = Sphere{f.p(0.1, 0.2, -0.3), f.len(0.3)}](CollisionWorld& w) { return w.overlapsVolume(cube(w), s); });
  volume("volume: sphere beside the cube", WorldOp::MeshSphereVolume, false,
         [cube, s = Sphere{f.p(2, 0, 0), f.len(0.5)}](CollisionWorld& w) { return w.overlapsVolume(cube(w), s); });
  volume("volume: box wholly inside the cube", WorldOp::MeshAabbVolume, true,
         [cube, b = Aabb{f.p(-0.5, -0.5, -0.5), f.p(0.5, 0.25, 0)}](CollisionWorld& w) {
           return w.overlapsVolume(cube(w), b);
         });
  volume("volume: box above the cube", WorldOp::MeshAabbVolume, false,
         [cube, b = Aabb{f.p(-0.5, -0.5, 1.5), f.p(0.5, 0.25, 2)}](CollisionWorld& w) {
           return w.overlapsVolume(cube(w), b);
         });
  volume("volume: turned box wholly inside the cube", WorldOp::MeshObbVolume, true,
         [cube, b = obb(f.p(0.1, 0, 0), f.v(0.4, 0.3, 0.2), rotationAbout(Vec3d(1, 2, 3), 40))](CollisionWorld& w) {
           return w.overlapsVolume(cube(w), b);
         });
  volume("volume: small triangle wholly inside the cube", WorldOp::MeshTriangleVolume, true,
         [cube, t = Triangle{f.p(-0.3, -0.3, 0), f.p(0.3, -0.3, 0), f.p(0, 0.3, 0)}](CollisionWorld& w) {
           return w.overlapsVolume(cube(w), t);
         });
  volume("volume: triangle 2 above the cube", WorldOp::MeshTriangleVolume, false,
         [cube, t = Triangle{f.p(-0.3, -0.3, 3), f.p(0.3, -0.3, 3), f.p(0, 0.3, 3)}](CollisionWorld& w) {
           return w.overlapsVolume(cube(w), t);
         });
  return cs;
}

// ---------------------------------------------------------------------------------------------
// The suite.

class OracleSanity : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const std::string_view name : builtBackends()) worlds_.push_back(makeWorld(name));
  }
  std::vector<std::unique_ptr<CollisionWorld>> worlds_;
};

const std::vector<Frame>& frames() {
  static const std::vector<Frame> fs = {{1, Vec3d::Zero()}, {0.01, Vec3d(0.07, -0.02, 0.05)},
                                        {100, Vec3d(700, -300, 250)}, {1, Vec3d(7.25, -2.5, 3.75)}};
  return fs;
}

bool close(const Vec3d& a, const Vec3d& b, double tol) { return (a - b).cwiseAbs().maxCoeff() <= tol; }

/// Runs every case of `cases` on every backend that supports its op.
void runCases(std::vector<std::unique_ptr<CollisionWorld>>& worlds, const Frame& frame,
              const std::vector<Case>& cases, std::map<std::string, int>& answered) {
  for (auto& world : worlds) {
    if (!frame.within(world->tolerance())) {
      std::printf("%s: %s is outside its working range (min feature %g): skipped\n",
                  std::string(world->backend()).c_str(), frame.name().c_str(), world->tolerance().minFeature);
      continue;
    }
    for (const Case& c : cases) {
      if (c.gap * frame.scale < 5 * world->tolerance().at(frame.magnitude())) continue;  // not clear for it
      const std::string where = std::string(world->backend()) + " / " + std::string(opName(c.op)) + " / " + c.name +
                                " / " + frame.name();
      if (!world->supports(c.op)) {
        EXPECT_THROW(c.run(*world), Unsupported) << where;
        continue;
      }
      Answer got;
      try {
        got = c.run(*world);
      } catch (const std::exception& e) {
        ADD_FAILURE() << where << ": threw " << e.what();
        continue;
      }
      ++answered[std::string(world->backend())];
      const Answer& want = c.expected;
      // The backend's error, plus the inputs' rounding to Real (the expectations are computed
      // from the unrounded canonical coordinates).
      const double tol = 4 * (world->tolerance().at(frame.magnitude()) +
                              2 * std::numeric_limits<Real>::epsilon() * frame.magnitude());
      EXPECT_EQ(got.hit, want.hit) << where;
      if (want.point && got.point) {
        EXPECT_TRUE(close(*got.point, *want.point, tol))
            << where << ": point " << str(*got.point) << ", want " << str(*want.point) << " (tolerance " << tol << ")";
      }
      if (want.point && want.hit) {
        EXPECT_TRUE(got.point.has_value()) << where << ": no point";
      }
      if (want.t && got.t) {
        EXPECT_NEAR(*got.t, *want.t, tol) << where;
      }
      if (want.normal && got.normal) {
        EXPECT_TRUE(close(*got.normal, *want.normal, 2 * tol / frame.scale))
            << where << ": normal " << str(*got.normal) << ", want " << str(*want.normal);
      }
      EXPECT_EQ(got.names, want.names) << where;
      EXPECT_EQ(got.allT.size(), want.allT.size()) << where;
      for (std::size_t i = 0; i < std::min(got.allT.size(), want.allT.size()); ++i)
        EXPECT_NEAR(got.allT[i], want.allT[i], tol) << where << ": hit " << i;
    }
  }
}

TEST_F(OracleSanity, NativeAndExactAreAlwaysBuilt) {
  const auto& built = builtBackends();
  EXPECT_NE(std::find(built.begin(), built.end(), "native"), built.end());
  EXPECT_NE(std::find(built.begin(), built.end(), "exact"), built.end());
  std::string list;
  for (const auto& w : worlds_) list += "  " + std::string(w->backend()) + ": " + w->description() + "\n";
  std::printf("backends built:\n%s", list.c_str());
}

TEST_F(OracleSanity, PrimitiveOpsAnswerAsDesigned) {
  std::map<std::string, int> answered;
  std::printf("%zu primitive cases x %zu frames\n", primitiveCases(Frame{}).size(), frames().size());
  for (const Frame& f : frames()) runCases(worlds_, f, primitiveCases(f), answered);
  for (const auto& w : worlds_) {
    std::printf("  %-7s answered %d\n", std::string(w->backend()).c_str(), answered[std::string(w->backend())]);
    EXPECT_GT(answered[std::string(w->backend())], 0) << w->backend();
  }
}

TEST_F(OracleSanity, MeshOpsAnswerAsDesigned) {
  std::map<std::string, int> answered;
  std::printf("%zu mesh cases x %zu frames\n", meshCases(Frame{}).size(), frames().size());
  for (const Frame& f : frames()) {
    for (auto& w : worlds_) addMeshes(*w, f);
    runCases(worlds_, f, meshCases(f), answered);
  }
  for (const auto& w : worlds_) {
    std::printf("  %-7s answered %d\n", std::string(w->backend()).c_str(), answered[std::string(w->backend())]);
    EXPECT_GT(answered[std::string(w->backend())], 0) << w->backend();
  }
}

/// Narrow phase: distances, contacts, point_inside and volume mode, on every backend
/// that supports them (native answers all; exact: point_inside and volume; fcl: distances;
/// bullet: contacts).
TEST_F(OracleSanity, NarrowPhaseOpsAnswerAsDesigned) {
  std::map<std::string, int> answered;
  std::printf("%zu narrow-phase cases x %zu frames\n", narrowPhaseCases(Frame{}).size(), frames().size());
  for (const Frame& f : frames()) {
    for (auto& w : worlds_) addMeshes(*w, f);
    runCases(worlds_, f, narrowPhaseCases(f), answered);
  }
  for (const auto& w : worlds_)
    std::printf("  %-7s answered %d\n", std::string(w->backend()).c_str(), answered[std::string(w->backend())]);
  EXPECT_GT(answered["native"], 0);
}

/// Closest ray hits on the grid land on triangles that contain the hit point, and every backend
/// names the same triangle (the cases avoid the grid's edges).
TEST_F(OracleSanity, RayHitsNameTheSameTriangle) {
  const Frame f;
  const Ray rays[] = {{f.p(0.3, 0.2, 5), f.v(0, 0, -1)}, {f.p(-2.6, 1.7, -2), f.v(1, -1, 1)},
                      {f.p(3.7, -3.4, 1), f.v(-0.1, 0.2, -1)}};
  std::vector<std::optional<std::uint32_t>> first(std::size(rays));
  for (auto& w : worlds_) {
    if (!w->supports(WorldOp::MeshRay)) continue;
    addMeshes(*w, f);
    const MeshHandle grid = w->meshHandle("grid");
    for (std::size_t i = 0; i < std::size(rays); ++i) {
      RayHitCollector hits;
      w->raycast(grid, rays[i], hits);
      ASSERT_TRUE(hits.hit()) << w->backend() << " ray " << i;
      const WorldRayHit h = *hits.hit();
      const Triangle t = w->mesh(grid).triangle(h.triangle);
      // The hit lies in the triangle's xy projection (z = 0 everywhere), well inside.
      const Vec3d p = h.point;
      const Vec3d a = t.a.cast<double>(), b = t.b.cast<double>(), c = t.c.cast<double>();
      auto edge = [&](const Vec3d& u, const Vec3d& v) { return (v.x() - u.x()) * (p.y() - u.y()) - (v.y() - u.y()) * (p.x() - u.x()); };
      EXPECT_GT(edge(a, b), 0) << w->backend() << " ray " << i << " triangle " << h.triangle << " point " << str(p);
      EXPECT_GT(edge(b, c), 0) << w->backend() << " ray " << i << " triangle " << h.triangle << " point " << str(p);
      EXPECT_GT(edge(c, a), 0) << w->backend() << " ray " << i << " triangle " << h.triangle << " point " << str(p);
      if (!first[i]) first[i] = h.triangle;
      EXPECT_EQ(h.triangle, *first[i]) << w->backend() << " ray " << i;
    }
  }
}

/// Every op a backend does not support throws Unsupported with the protocol's message.
TEST_F(OracleSanity, UnsupportedOpsSaySo) {
  const Frame f;
  const Triangle T = canonicalTriangle(f);
  for (auto& w : worlds_) {
    addMeshes(*w, f);
    const MeshHandle cube = w->meshHandle("cube");
    int unsupported = 0;
    for (const WorldOp op : allWorldOps()) {
      if (w->supports(op)) continue;
      ++unsupported;
      const std::string want = "unsupported: " + std::string(opName(op)) + " on " + std::string(w->backend());
      const ModelHandle model{0};
      RayHitCollector hits;
      const std::function<void()> calls[] = {
          [&] { w->closestPoint(T, f.p(1, 1, 1)); },
          [&] { w->overlaps(T, Sphere{f.p(1, 1, 1), 1}); },
          [&] { w->overlaps(T, Aabb{f.p(0, 0, 0), f.p(1, 1, 1)}); },
          [&] { w->overlaps(T, Obb{}); },
          [&] { w->overlaps(T, Plane{}); },
          [&] { w->overlaps(T, T); },
          [&] { w->raycast(Ray{}, T); },
          [&] { w->intersects(Segment{}, T); },
          [&] { throw Unsupported(WorldOp::Mesh, w->backend()); },      // defining meshes: always supported
          [&] { throw Unsupported(WorldOp::LoadMesh, w->backend()); },  // (not reached)
          [&] { w->raycast(cube, Ray{}, hits); },
          [&] { w->intersects(cube, Segment{}); },
          [&] { w->overlaps(cube, Sphere{}); },
          [&] { w->overlaps(cube, Aabb{}); },
          [&] { w->overlaps(cube, Obb{}); },
          [&] { w->overlaps(cube, Plane{}); },
          [&] { w->overlaps(cube, T); },
          [&] { w->overlaps(cube, Transform{}, cube, Transform{}); },
          [&] { w->addModel("m", cube); },
          [&] { w->setTransform(model, Transform{}); },
          [&] { w->setParent(model, std::nullopt); },
          [&] { w->removeModel(model); },
          [&] { w->descendants(model); },
          [&] { w->raycast(model, Ray{}, hits); },
          [&] { w->intersects(model, Segment{}); },
          [&] { w->overlaps(model, Sphere{}); },
          [&] { w->overlaps(model, Aabb{}); },
          [&] { w->overlaps(model, Obb{}); },
          [&] { w->overlaps(model, Plane{}); },
          [&] { w->overlaps(model, T); },
          [&] { w->sceneRaycast(Ray{}, hits); },
          [&] { w->sceneQuery(Sphere{}); },
          [&] { w->scenePairs(); },
          [&] { w->contacts({Sphere{}, Transform{}}, {cube, Transform{}}, 0); },
          [&] { w->distance({Sphere{}, Transform{}}, {cube, Transform{}}); },
          [&] { w->meshDistance(cube, Transform{}, cube, Transform{}); },
          [&] { w->modelDistance(model, model); },
          [&] { w->pointInside(cube, f.p(0, 0, 0)); },
          [&] { w->overlapsVolume(cube, Sphere{}); },
          [&] { w->overlapsVolume(cube, Aabb{}); },
          [&] { w->overlapsVolume(cube, Obb{}); },
          [&] { w->overlapsVolume(cube, T); },
          [&] { w->overlapsVolume(cube, Transform{}, cube, Transform{}); },
          [&] { w->overlapsVolume(model, Sphere{}); },
          [&] { w->overlapsVolume(model, Aabb{}); },
          [&] { w->overlapsVolume(model, Obb{}); },
          [&] { w->overlapsVolume(model, T); },
          [&] { w->cast({Sphere{}, Transform{}}, WorldMotion{}, {cube, Transform{}}); },
          [&] { w->modelCast({Sphere{}, Transform{}}, WorldMotion{}, model); },
          [&] { w->sceneCast({Sphere{}, Transform{}}, WorldMotion{}); },
      };
      static_assert(std::size(calls) == kWorldOpCount, "one call per op");
      try {
        calls[std::size_t(op)]();
        ADD_FAILURE() << w->backend() << " / " << opName(op) << ": answered although unsupported";
      } catch (const Unsupported& e) {
        EXPECT_EQ(std::string(e.what()), want);
        EXPECT_EQ(e.op(), op);
      } catch (const std::exception& e) {
        ADD_FAILURE() << w->backend() << " / " << opName(op) << ": threw " << e.what() << " instead of Unsupported";
      }
    }
    std::printf("%-7s answers %zu of %zu ops\n", std::string(w->backend()).c_str(), kWorldOpCount - unsupported,
                kWorldOpCount);
  }
}

// ---------------------------------------------------------------------------------------------
// Models and the scene. Shapes are in world space; each stage's cases are designed from the world
// poses stated next to them (cube0 = [-1,1]³ and small0 = [-0.3,0.3]³ about the model's origin).

/// A transform: rotation, then translation by the frame point (x, y, z) (roots) or by the frame
/// vector (children: relative to the parent, so the frame's offset must not be added twice).
Transform at(const Frame& f, double x, double y, double z, const Quat& q = Quat::Identity(), bool root = true) {
  Transform t;
  t.rotation = q;
  t.translation = root ? f.p(x, y, z) : f.v(x, y, z);
  return t;
}

/// The name of the model a hit names, or "?".
std::string modelName(CollisionWorld& w, ModelHandle h, const std::vector<std::string>& names) {
  for (const std::string& n : names)
    if (const auto m = w.findModel(n); m && *m == h) return n;
  return "?";
}

Answer namesAnswer(std::vector<std::string> names) {
  Answer a;
  a.hit = !names.empty();
  a.names = std::move(names);
  return a;
}

/// Single-model cases (model_*) and children; `stage` selects the hierarchy's state:
/// 0: base = cube0 at (3,0,0) turned 90° about z; arm = cube0, child of base at local (0,4,0),
///    so at world (-1,0,0); tip = small0, child of arm at local (0,0,3), so at world (-1,0,3).
/// 1: after set_transform(base, (0,5,0), no rotation): arm at (0,9,0), tip at (0,9,3).
/// 2: after remove_model(base) and set_parent(tip, none): poses as in stage 1; arm has no children.
std::vector<Case> modelCases(const Frame& f, int stage) {
  std::vector<Case> cs;
  auto boolean = [&](const std::string& name, WorldOp op, bool expect, std::function<bool(CollisionWorld&, ModelHandle)> q,
                     std::string model, double gap = 0.05) {
    cs.push_back({name + " (" + model + ")", op,
                  [q, model](CollisionWorld& w) {
                    const auto h = w.findModel(model);
                    if (!h) throw std::runtime_error("no model " + model);
                    return hitAnswer(q(w, *h));
                  },
                  hitAnswer(expect), gap});
  };
  auto sphere = [&](const std::string& name, const std::string& model, Vec3 c, double r, bool expect, double gap) {
    const Sphere s{c, f.len(r)};
    boolean(name, WorldOp::ModelSphere, expect, [s](CollisionWorld& w, ModelHandle h) { return w.overlaps(h, s); },
            model, gap);
  };
  auto segment = [&](const std::string& name, const std::string& model, Vec3 a, Vec3 b, bool expect) {
    const Segment s{a, b};
    boolean(name, WorldOp::ModelSegment, expect, [s](CollisionWorld& w, ModelHandle h) { return w.intersects(h, s); },
            model);
  };
  auto children = [&](const std::string& model, std::vector<std::string> want) {
    Answer a = namesAnswer(want);
    a.hit = true;
    cs.push_back({"children of " + model, WorldOp::Children,
                  [model](CollisionWorld& w) {
                    Answer got;
                    got.hit = true;
                    got.names = w.descendants(*w.findModel(model));
                    return got;
                  },
                  a});
  };
  if (stage == 0) {
    sphere("sphere 0.1 deep in the arm's top face", "arm", f.p(-1, 0, 1.5), 0.6, true, 0.1);
    sphere("sphere 0.1 above the arm's top face", "arm", f.p(-1, 0, 1.7), 0.6, false, 0.1);
    sphere("sphere 0.5 deep in the base's +x face", "base", f.p(4.5, 0, 0), 1, true, 0.5);
    sphere("sphere at the arm, far from the base", "base", f.p(-1, 0, 1.5), 0.6, false, 0.5);
    const Aabb across{f.p(-1.1, -0.1, 3.2), f.p(-0.9, 0.1, 3.5)}, above{f.p(-1.1, -0.1, 3.4), f.p(-0.9, 0.1, 3.6)};
    boolean("box across the tip's top face", WorldOp::ModelAabb, true,
            [across](CollisionWorld& w, ModelHandle h) { return w.overlaps(h, across); }, "tip", 0.1);
    boolean("box 0.1 above the tip", WorldOp::ModelAabb, false,
            [above](CollisionWorld& w, ModelHandle h) { return w.overlaps(h, above); }, "tip", 0.1);
    // A unit box turned 45° about z reaches 0.707 from its centre along x; the arm spans x in [-2, 0].
    const Quat z45 = rotationAbout(Vec3d::UnitZ(), 45);
    const Obb deep = obb(f.p(0.2, 0, 0), f.v(0.5, 0.5, 0.5), z45), apart = obb(f.p(0.9, 0, 0), f.v(0.5, 0.5, 0.5), z45);
    boolean("turned box 0.5 deep in the arm", WorldOp::ModelObb, true,
            [deep](CollisionWorld& w, ModelHandle h) { return w.overlaps(h, deep); }, "arm", 0.19);
    boolean("turned box 0.19 from the arm", WorldOp::ModelObb, false,
            [apart](CollisionWorld& w, ModelHandle h) { return w.overlaps(h, apart); }, "arm", 0.19);
    // Planes x = 3 (through the base, which spans x in [2, 4]) and x = 4.5.
    const Plane through{Vec3(1, 0, 0), Real(f.scale * 3 + f.offset.x())},
        beside{Vec3(1, 0, 0), Real(f.scale * 4.5 + f.offset.x())};
    boolean("plane x = 3 through the base", WorldOp::ModelPlane, true,
            [through](CollisionWorld& w, ModelHandle h) { return w.overlaps(h, through); }, "base", 0.5);
    boolean("plane x = 4.5 beside the base", WorldOp::ModelPlane, false,
            [beside](CollisionWorld& w, ModelHandle h) { return w.overlaps(h, beside); }, "base", 0.5);
    const Triangle crossing{f.p(-1, -0.5, 0.5), f.p(-1, 0.5, 0.5), f.p(-1, 0, 2)},
        over{f.p(-1, -0.5, 1.5), f.p(-1, 0.5, 1.5), f.p(-1, 0, 2)};
    boolean("triangle through the arm's top face", WorldOp::ModelTriangle, true,
            [crossing](CollisionWorld& w, ModelHandle h) { return w.overlaps(h, crossing); }, "arm", 0.5);
    boolean("triangle 0.5 above the arm", WorldOp::ModelTriangle, false,
            [over](CollisionWorld& w, ModelHandle h) { return w.overlaps(h, over); }, "arm", 0.5);
    segment("segment through the tip", "tip", f.p(-1, 0, 2), f.p(-1, 0, 4), true);
    segment("segment 0.7 beside the tip", "tip", f.p(0, 0, 2), f.p(0, 0, 4), false);
    // Rays down from (-1, 0, 5): the arm's top face z = 1 at t = 4; the base is elsewhere.
    const Ray down{f.p(-1, 0.2, 5), f.v(0, 0, -1)};
    Answer top;
    top.hit = true;
    top.t = 4 * f.scale;
    top.point = f.expectP(-1, 0.2, 1);
    top.normal = Vec3d(0, 0, 1);
    cs.push_back({"ray down onto the arm", WorldOp::ModelRay,
                  [down](CollisionWorld& w) {
                    RayHitCollector hits;
                    w.raycast(*w.findModel("arm"), down, hits);
                    return rayAnswer(hits.hit());
                  },
                  top});
    cs.push_back({"ray down beside the base", WorldOp::ModelRay,
                  [down](CollisionWorld& w) {
                    RayHitCollector hits;
                    w.raycast(*w.findModel("base"), down, hits);
                    return rayAnswer(hits.hit());
                  },
                  hitAnswer(false)});
    children("base", {"arm", "tip"});
    children("arm", {"tip"});
  } else {
    sphere("sphere where the arm was", "arm", f.p(-1, 0, 1.5), 0.6, false, 0.1);
    sphere("sphere 0.1 deep in the moved arm's top face", "arm", f.p(0, 9, 1.5), 0.6, true, 0.1);
    segment("segment through the moved tip", "tip", f.p(0, 9, 2), f.p(0, 9, 4), true);
    segment("segment where the tip was", "tip", f.p(-1, 0, 2), f.p(-1, 0, 4), false);
    children("arm", stage == 1 ? std::vector<std::string>{"tip"} : std::vector<std::string>{});
  }
  return cs;
}

void addModels(CollisionWorld& w, const Frame& f) {
  const ModelHandle base = w.addModel("base", w.meshHandle("cube0"), at(f, 3, 0, 0, rotationAbout(Vec3d::UnitZ(), 90)));
  const ModelHandle arm = w.addModel("arm", w.meshHandle("cube0"), at(f, 0, 4, 0, Quat::Identity(), false), base);
  w.addModel("tip", w.meshHandle("small0"), at(f, 0, 0, 3, Quat::Identity(), false), arm);
}

TEST_F(OracleSanity, ModelOpsAnswerAsDesigned) {
  std::map<std::string, int> answered;
  for (const Frame& f : frames()) {
    std::vector<std::unique_ptr<CollisionWorld>> worlds;
    for (const std::string_view name : builtBackends()) {
      auto w = makeWorld(name);
      if (!w->supports(WorldOp::AddModel)) continue;
      addMeshes(*w, f);
      addModels(*w, f);
      worlds.push_back(std::move(w));
    }
    runCases(worlds, f, modelCases(f, 0), answered);
    for (auto& w : worlds)
      if (w->supports(WorldOp::SetTransform)) w->setTransform(*w->findModel("base"), at(f, 0, 5, 0));
    runCases(worlds, f, modelCases(f, 1), answered);
    for (auto& w : worlds) {
      if (!w->supports(WorldOp::RemoveModel) || !w->supports(WorldOp::SetParent)) continue;
      w->removeModel(*w->findModel("base"));
      EXPECT_FALSE(w->findModel("base")) << w->backend();
      w->setParent(*w->findModel("tip"), std::nullopt);
    }
    runCases(worlds, f, modelCases(f, 2), answered);
  }
  for (const auto& [backend, n] : answered) std::printf("  %-7s answered %d model cases\n", backend.c_str(), n);
}

/// Scene: a = cube0 at (0,0,0); b = cube0 at (1.5,0.3,0.2) (0.5 into a); c = small0 at (10,0,0);
/// d = cube0 at (0,0,2.5) turned 45° about z (its bottom z = 1.5 is 0.3 above b's top, 0.5 above a's).
std::vector<Case> sceneCases(const Frame& f) {
  std::vector<Case> cs;
  auto query = [&](const std::string& name, SceneQueryShape shape, bool boundsOnly, std::vector<std::string> want,
                   double gap = 0.05) {
    cs.push_back({name, WorldOp::SceneQuery,
                  [shape, boundsOnly](CollisionWorld& w) { return namesAnswer(w.sceneQuery(shape, boundsOnly)); },
                  namesAnswer(want), gap});
  };
  query("sphere 0.25 into a's -x face", Sphere{f.p(-1.5, 0, 0), f.len(0.75)}, false, {"a"}, 0.25);
  query("sphere 0.1 into c's top", Sphere{f.p(10, 0, 0.6), f.len(0.4)}, false, {"c"}, 0.1);
  query("sphere in empty space", Sphere{f.p(5, 5, 5), f.len(1)}, false, {}, 1);
  query("box across a's -x face", Aabb{f.p(-1.2, -0.1, -0.1), f.p(-0.8, 0.1, 0.1)}, false, {"a"}, 0.2);
  query("turned box across c's +x face", obb(f.p(10.35, 0, 0), f.v(0.1, 0.1, 0.1), rotationAbout(Vec3d(1, 2, 3), 40)),
        false, {"c"}, 0.05);
  query("bounds: sphere in empty space", Sphere{f.p(5, 5, 5), f.len(1)}, true, {}, 1);
  query("bounds: sphere 0.25 into a's box", Sphere{f.p(-1.5, 0, 0), f.len(0.75)}, true, {"a"}, 0.25);
  cs.push_back({"pairs", WorldOp::ScenePairs,
                [](CollisionWorld& w) {
                  std::vector<std::string> names;
                  for (const auto& [a, b] : w.scenePairs()) names.push_back(a + "|" + b);
                  return namesAnswer(names);
                },
                namesAnswer({"a|b"}), 0.3});
  // A ray along +x at y = 0.5, z = 0.3: a's faces x = -1 and 1 (t = 4, 6), b's x = 0.5 and 2.5 (t = 5.5, 7.5).
  const Ray r{f.p(-5, 0.5, 0.3), f.v(1, 0, 0)};
  const std::vector<std::string> all = {"a", "b", "c", "d"};
  Answer first;
  first.hit = true;
  first.t = 4 * f.scale;
  first.point = f.expectP(-1, 0.5, 0.3);
  first.normal = Vec3d(-1, 0, 0);
  first.names = {"a"};
  cs.push_back({"closest ray hit", WorldOp::SceneRay,
                [r, all](CollisionWorld& w) {
                  RayHitCollector hits;
                  w.sceneRaycast(r, hits);
                  Answer a = rayAnswer(hits.hit());
                  if (hits.hit()) a.names = {modelName(w, hits.hit()->model, all)};
                  return a;
                },
                first, 0.5});
  Answer every;
  every.hit = true;
  every.allT = {4 * f.scale, 5.5 * f.scale, 6 * f.scale, 7.5 * f.scale};
  every.names = {"a", "b", "a", "b"};
  cs.push_back({"every ray hit", WorldOp::SceneRay,
                [r, all](CollisionWorld& w) {
                  RayHitCollector hits(RayCollect::All);
                  w.sceneRaycast(r, hits);
                  Answer a;
                  a.hit = hits.hasHit();
                  for (const WorldRayHit& h : hits.hits()) {
                    a.allT.push_back(h.t);
                    a.names.push_back(modelName(w, h.model, all));
                  }
                  return a;
                },
                every, 0.5});
  return cs;
}

TEST_F(OracleSanity, SceneOpsAnswerAsDesigned) {
  std::map<std::string, int> answered;
  for (const Frame& f : frames()) {
    std::vector<std::unique_ptr<CollisionWorld>> worlds;
    for (const std::string_view name : builtBackends()) {
      auto w = makeWorld(name);
      if (!w->supports(WorldOp::AddModel)) continue;
      addMeshes(*w, f);
      w->addModel("a", w->meshHandle("cube0"), at(f, 0, 0, 0));
      w->addModel("b", w->meshHandle("cube0"), at(f, 1.5, 0.3, 0.2));
      w->addModel("c", w->meshHandle("small0"), at(f, 10, 0, 0));
      w->addModel("d", w->meshHandle("cube0"), at(f, 0, 0, 2.5, rotationAbout(Vec3d::UnitZ(), 45)));
      worlds.push_back(std::move(w));
    }
    runCases(worlds, f, sceneCases(f), answered);
  }
  for (const auto& [backend, n] : answered) std::printf("  %-7s answered %d scene cases\n", backend.c_str(), n);
}

// ---------------------------------------------------------------------------------------------
// The factory and the boundary.

TEST(WorldFactory, MakesEveryBuiltBackendUnderItsName) {
  ASSERT_EQ(knownBackends(), (std::vector<std::string_view>{"native", "fcl", "bullet", "exact"}));
  for (const std::string_view name : builtBackends()) {
    const auto w = makeWorld(name);
    ASSERT_TRUE(w);
    EXPECT_EQ(w->backend(), name);
    EXPECT_FALSE(w->description().empty());
    const WorldTolerance t = w->tolerance();
    EXPECT_GT(t.relative, 0);
    EXPECT_LT(t.relative, 1e-2);
    EXPECT_GE(t.absolute, 0);
    EXPECT_GE(t.minFeature, 0);
    EXPECT_TRUE(w->supports(WorldOp::Mesh));
  }
}

TEST(WorldFactory, UnknownBackendIsInvalidInputNamingIt) {
  try {
    makeWorld("havok");
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("havok"), std::string::npos) << what;
    EXPECT_NE(what.find("native"), std::string::npos) << what;
  }
}

/// A backend whose peer throws: the world's edge reports BackendFailure, lets Unsupported and
/// InvalidInput through unchanged, and stays usable.
class ThrowingWorld final : public CollisionWorld {
 public:
  std::string_view backend() const override { return "throwing"; }
  std::string description() const override { return "test double"; }
  bool supports(WorldOp op) const override { return op == WorldOp::TriangleSphere || op == WorldOp::TriangleAabb; }
  WorldTolerance tolerance() const override { return {}; }
  int calls = 0;

 protected:
  void onMeshAdded(MeshHandle, const Mesh& mesh) override {
    if (mesh.name() == "bad") throw std::runtime_error("peer cannot build this mesh");
  }
  void onMeshRemoved(MeshHandle) override {}
  bool doOverlaps(const Triangle&, const Sphere&) override {
    ++calls;
    throw std::runtime_error("peer exploded");
  }
  bool doOverlaps(const Triangle&, const Aabb&) override {
    ++calls;
    throw 42;  // not even a std::exception
  }
};

TEST(WorldBoundary, PeerExceptionsBecomeBackendFailure) {
  ThrowingWorld w;
  const Triangle t{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  try {
    w.overlaps(t, Sphere{Vec3::Zero(), 1});
    FAIL() << "no exception";
  } catch (const BackendFailure& e) {
    EXPECT_EQ(std::string(e.what()), "throwing failed on triangle_sphere: peer exploded");
    EXPECT_EQ(e.op(), WorldOp::TriangleSphere);
  }
  EXPECT_THROW(w.overlaps(t, Aabb{Vec3::Zero(), Vec3::Ones()}), BackendFailure);
  EXPECT_THROW(w.overlaps(t, Plane{}), Unsupported);
  // Input is validated before the backend sees it.
  const int before = w.calls;
  EXPECT_THROW(w.overlaps(t, Sphere{Vec3::Zero(), -1}), InvalidInput);
  EXPECT_EQ(w.calls, before);
  // A mesh the peer cannot build is not added, and an older mesh of that name stays.
  const auto ok = boxMesh(Vec3::Zero(), Vec3::Ones(), "ok");
  const MeshHandle h = w.addMesh("m", ok);
  EXPECT_THROW(w.addMesh("m", boxMesh(Vec3::Zero(), Vec3::Ones(), "bad")), BackendFailure);
  ASSERT_TRUE(w.findMesh("m"));
  EXPECT_EQ(*w.findMesh("m"), h);
  EXPECT_EQ(&w.mesh(h), ok.get());
}

}  // namespace
}  // namespace crux
