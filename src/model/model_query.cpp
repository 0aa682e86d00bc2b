/// @file model_query.cpp  Queries against placed meshes: map the query into mesh space, run the
/// mesh query, map hits back (see model_query.hpp for the mapping of each shape).

#include <crux/model/model_query.hpp>

#include "rigid.hpp"

#include <algorithm>

namespace crux {
namespace {

using model_detail::RigidFrame;

Ray toMesh(const RigidFrame& f, const Ray& r) { return {f.toMesh(r.origin), f.toMeshVector(r.dir)}; }

MeshRayHit toWorld(const RigidFrame& f, MeshRayHit h) {
  h.point = f.toWorld(h.point);
  h.normal = f.toWorldVector(h.normal);
  return h;
}

/// An AABB given by two corners' images under a signed permutation (exact): per-axis min/max.
Aabb boxOfCorners(const Vec3& p, const Vec3& q) { return {p.cwiseMin(q), q.cwiseMax(p)}; }

Real maxAbs(const Aabb& b) { return std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff()); }

/// World bounds under an axis-aligned rotation: the exact image of the local box, with the
/// translation added with outward rounding.
Aabb alignedWorldBounds(const RigidFrame& f, const Aabb& local) {
  const Aabb r = boxOfCorners(f.rotation() * local.min, f.rotation() * local.max);  // exact
  Aabb out;
  for (int i = 0; i < 3; ++i) {
    out.min[i] = model_detail::addDown(r.min[i], f.translation()[i]);
    out.max[i] = model_detail::addUp(r.max[i], f.translation()[i]);
  }
  return out;
}

/// Absolute pad of the bounds under a general rotation.
Real generalPad(const RigidFrame& f, const Aabb& local) {
  return kWorldBoundsPad * (maxAbs(local) + f.translation().cwiseAbs().maxCoeff());
}

}  // namespace

std::optional<MeshRayHit> model_detail::raycastClosest(const Mesh& mesh, const RigidFrame& f, const Ray& worldRay,
                                                      const RayQueryOptions& options) {
  if (f.identity()) return crux::raycastClosest(mesh, worldRay, options);
  std::optional<MeshRayHit> h = crux::raycastClosest(mesh, toMesh(f, worldRay), options);
  if (h) *h = toWorld(f, *h);
  return h;
}

std::optional<MeshRayHit> raycastClosest(const PlacedMesh& m, const Ray& worldRay, const RayQueryOptions& options) {
  return model_detail::raycastClosest(*m.mesh, RigidFrame(m.world), worldRay, options);
}

bool raycastAny(const PlacedMesh& m, const Ray& worldRay, const RayQueryOptions& options) {
  const RigidFrame f(m.world);
  if (f.identity()) return raycastAny(*m.mesh, worldRay, options);
  return raycastAny(*m.mesh, toMesh(f, worldRay), options);
}

std::vector<MeshRayHit> raycastAll(const PlacedMesh& m, const Ray& worldRay, const RayQueryOptions& options) {
  const RigidFrame f(m.world);
  if (f.identity()) return raycastAll(*m.mesh, worldRay, options);
  std::vector<MeshRayHit> hits = raycastAll(*m.mesh, toMesh(f, worldRay), options);
  for (MeshRayHit& h : hits) h = toWorld(f, h);
  return hits;
}

bool intersects(const PlacedMesh& m, const Segment& s) {
  const RigidFrame f(m.world);
  if (f.identity()) return intersects(*m.mesh, s);
  return intersects(*m.mesh, Segment{f.toMesh(s.start), f.toMesh(s.end)});
}

bool overlaps(const PlacedMesh& m, const Sphere& s) {
  const RigidFrame f(m.world);
  if (f.identity()) return overlaps(*m.mesh, s);
  return overlaps(*m.mesh, Sphere{f.toMesh(s.center), s.radius});
}

bool overlaps(const PlacedMesh& m, const Aabb& b) {
  const RigidFrame f(m.world);
  if (f.identity()) return overlaps(*m.mesh, b);
  if (f.axisAligned()) return overlaps(*m.mesh, boxOfCorners(f.toMesh(b.min), f.toMesh(b.max)));
  return overlaps(*m.mesh, Obb{f.toMesh(b.center()), b.half(), f.rotation().transpose()});
}

bool overlaps(const PlacedMesh& m, const Obb& b) {
  const RigidFrame f(m.world);
  if (f.identity()) return overlaps(*m.mesh, b);
  return overlaps(*m.mesh, Obb{f.toMesh(b.center), b.half, f.rotation().transpose() * b.axes});
}

bool overlaps(const PlacedMesh& m, const Plane& p) {
  const RigidFrame f(m.world);
  if (f.identity()) return overlaps(*m.mesh, p);
  // n·(R x + t) = d  <=>  (Rᵀn)·x = d - n·t; the distance is rounded once (from Wide).
  const Real d = Real(Wide(p.d) - wide(p.normal).dot(wide(f.translation())));
  return overlaps(*m.mesh, Plane{f.toMeshVector(p.normal), d});
}

bool overlaps(const PlacedMesh& m, const Triangle& t) {
  const RigidFrame f(m.world);
  if (f.identity()) return overlaps(*m.mesh, t);
  return overlaps(*m.mesh, Triangle{f.toMesh(t.a), f.toMesh(t.b), f.toMesh(t.c)});
}

bool overlaps(const PlacedMesh& a, const PlacedMesh& b) {
  const bool same = a.world.rotation.coeffs() == b.world.rotation.coeffs() && a.world.translation == b.world.translation;
  const Transform rel = same ? Transform::identity() : model_detail::relative(a.world, b.world);
  return overlaps(*a.mesh, Transform::identity(), *b.mesh, rel);
}

MeshMeshDistanceResult distance(const PlacedMesh& a, const PlacedMesh& b, const MeshDistanceOptions& options) {
  const bool same = a.world.rotation.coeffs() == b.world.rotation.coeffs() && a.world.translation == b.world.translation;
  const Transform rel = same ? Transform::identity() : model_detail::relative(a.world, b.world);
  MeshMeshDistanceResult r = distance(*a.mesh, Transform::identity(), *b.mesh, rel, options);
  if (r.found) {
    const RigidFrame f(a.world);
    r.pointA = f.toWorld(r.pointA);
    r.pointB = f.toWorld(r.pointB);
  }
  return r;
}

Aabb worldBounds(const PlacedMesh& m) {
  const Aabb& local = m.mesh->bounds();
  const RigidFrame f(m.world);
  if (f.identity()) return local;
  if (f.axisAligned()) return alignedWorldBounds(f, local);
  const Vec3 c = f.toWorld(local.center());
  const Vec3 ext = f.rotation().cwiseAbs() * local.half() + Vec3::Constant(generalPad(f, local));
  return {c - ext, c + ext};
}

Obb worldObb(const PlacedMesh& m) {
  const Aabb& local = m.mesh->bounds();
  const RigidFrame f(m.world);
  if (f.axisAligned()) {
    // The OBB with axes R (a signed permutation) is the world AABB; its half extents along the
    // box axes are the world half extents permuted back. Centre and half extents are rounded
    // outwards so that the box still contains the exact bounds.
    const Aabb w = f.identity() ? local : alignedWorldBounds(f, local);
    Obb o;
    o.axes = f.rotation();
    o.center = w.center();
    Vec3 worldHalf;
    for (int i = 0; i < 3; ++i)
      worldHalf[i] = std::max(model_detail::addUp(w.max[i], -o.center[i]), model_detail::addUp(o.center[i], -w.min[i]));
    o.half = f.rotation().cwiseAbs().transpose() * worldHalf;  // exact: a permutation
    return o;
  }
  Obb o;
  o.axes = f.rotation();
  o.center = f.toWorld(local.center());
  o.half = local.half() + Vec3::Constant(generalPad(f, local));
  return o;
}

}  // namespace crux
