/// @file exact_world.cpp  The "exact" backend: the CGAL oracle of exact.hpp behind the
/// CollisionWorld interface, brute force over triangles (see exact_world.hpp).

#include "exact/exact_world.hpp"

#include "exact/exact.hpp"
#include "exact/exact_kernel.hpp"

#include <CGAL/Bbox_3.h>
#include <CGAL/intersections.h>
#include <CGAL/version_macros.h>

#include <cmath>
#include <variant>
#include <vector>

namespace crux::exact {
namespace {

using namespace detail;

/// The point / segment / triangle three exact points span (cf. detail::toSimplex, which takes
/// floating-point corners).
Simplex simplexOf(const Point& a, const Point& b, const Point& c) {
  if (!CGAL::collinear(a, b, c)) return Triangle3(a, b, c);
  if (a == b && b == c) return a;
  const FT ab = CGAL::squared_distance(a, b), bc = CGAL::squared_distance(b, c),
           ca = CGAL::squared_distance(c, a);
  if (ab >= bc && ab >= ca) return Segment3(a, b);
  if (bc >= ca) return Segment3(b, c);
  return Segment3(c, a);
}

/// A rigid transform with exact coefficients: x -> R x + t, R the rotation matrix of q/|q|,
/// (w²+x²-y²-z², 2(xy-wz), ...)/|q|², which is exactly orthogonal for any non-zero q.
struct ExactTransform {
  FT r[3][3];
  FT t[3];

  explicit ExactTransform(const Transform& tf) {
    const FT w(double(tf.rotation.w())), x(double(tf.rotation.x())), y(double(tf.rotation.y())),
        z(double(tf.rotation.z()));
    const FT n = w * w + x * x + y * y + z * z;
    r[0][0] = (w * w + x * x - y * y - z * z) / n;
    r[0][1] = 2 * (x * y - w * z) / n;
    r[0][2] = 2 * (x * z + w * y) / n;
    r[1][0] = 2 * (x * y + w * z) / n;
    r[1][1] = (w * w - x * x + y * y - z * z) / n;
    r[1][2] = 2 * (y * z - w * x) / n;
    r[2][0] = 2 * (x * z - w * y) / n;
    r[2][1] = 2 * (y * z + w * x) / n;
    r[2][2] = (w * w - x * x - y * y + z * z) / n;
    for (int i = 0; i < 3; ++i) t[i] = FT(double(tf.translation[i]));
  }

  Point apply(const Vec3& v) const {
    const FT p[3] = {FT(double(v.x())), FT(double(v.y())), FT(double(v.z()))};
    FT out[3];
    for (int i = 0; i < 3; ++i) out[i] = r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2] + t[i];
    return Point(out[0], out[1], out[2]);
  }
};

/// A mesh's triangles placed in the world exactly, with conservative boxes for the filter.
struct PlacedSimplices {
  std::vector<Simplex> simplices;
  std::vector<CGAL::Bbox_3> boxes;

  PlacedSimplices(const Mesh& mesh, const Transform& tf) {
    const ExactTransform xf(tf);
    std::vector<Point> points;
    points.reserve(mesh.vertexCount());
    for (const Vec3& v : mesh.vertices()) points.push_back(xf.apply(v));
    simplices.reserve(mesh.triangleCount());
    boxes.reserve(mesh.triangleCount());
    for (const TriangleIndices& t : mesh.triangles()) {
      const Point &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
      simplices.push_back(simplexOf(a, b, c));
      boxes.push_back(a.bbox() + b.bbox() + c.bbox());  // interval boxes: enclose the exact points
    }
  }
};

/// Exact back-face test of RayQueryOptions::cullBackFaces: ((b-a)×(c-a))·dir > 0.
bool backFacing(const Triangle& t, const Vec3& dir) {
  const Point a = toPoint(t.a);
  return CGAL::cross_product(toPoint(t.b) - a, toPoint(t.c) - a) * toVector(dir) > 0;
}

/// The hit at world distance t on triangle `tri`: point o + t·d/|d| and the normal facing the
/// origin (in-plane ray: the plane normal; degenerate triangle: -d/|d|), evaluated in double.
WorldRayHit makeHit(const Ray& r, const Triangle& tri, double t, std::uint32_t index) {
  const Vec3d o = r.origin.cast<double>(), d = r.dir.cast<double>();
  const Vec3d u = d / d.norm();
  WorldRayHit hit;
  hit.t = t;
  hit.point = o + t * u;
  hit.triangle = index;
  const Point a = toPoint(tri.a);
  const Vector n = CGAL::cross_product(toPoint(tri.b) - a, toPoint(tri.c) - a);
  if (n == CGAL::NULL_VECTOR) {
    hit.normal = -u;
    return hit;
  }
  const Vec3d nd(CGAL::to_double(n.x()), CGAL::to_double(n.y()), CGAL::to_double(n.z()));
  hit.normal = nd / nd.norm();
  if (n * toVector(r.dir) > 0) hit.normal = -hit.normal;
  return hit;
}

class ExactWorld final : public CollisionWorld {
 public:
  std::string_view backend() const override { return "exact"; }
  std::string description() const override {
    return "CGAL " CGAL_VERSION_STR " Epeck (exact rationals), brute force over triangles";
  }
  bool supports(WorldOp op) const override { return op <= WorldOp::MeshMesh; }
  WorldTolerance tolerance() const override { return kExactTolerance; }

 protected:
  void onMeshAdded(MeshHandle, const Mesh&) override {}
  void onMeshRemoved(MeshHandle) override {}

  Vec3d doClosestPoint(const Triangle& t, const Vec3& p) override { return exact::closestPoint(t, p); }
  bool doOverlaps(const Triangle& t, const Sphere& s) override { return exact::overlaps(t, s); }
  bool doOverlaps(const Triangle& t, const Aabb& b) override { return exact::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Obb& b) override { return exact::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Plane& p) override { return exact::overlaps(t, p); }
  bool doOverlaps(const Triangle& a, const Triangle& b) override { return exact::overlaps(a, b); }
  std::optional<WorldRayHit> doRaycast(const Ray& r, const Triangle& t) override {
    const std::optional<double> d = exact::raycast(r, t);
    if (!d) return std::nullopt;
    return makeHit(r, t, *d, 0);
  }
  bool doIntersects(const Segment& s, const Triangle& t) override { return exact::intersects(s, t); }

  void doRaycast(MeshHandle m, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    const Mesh& mesh = this->mesh(m);
    for (std::uint32_t i = 0; i < mesh.triangleCount() && !hits.done(); ++i) {
      const Triangle tri = mesh.triangle(i);
      if (options.cullBackFaces && backFacing(tri, r.dir)) continue;
      const std::optional<double> t = exact::raycast(r, tri);
      if (t && *t <= double(options.maxDistance)) hits.add(makeHit(r, tri, *t, i));
    }
  }
  bool doIntersects(MeshHandle m, const Segment& s) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::intersects(s, t); });
  }
  bool doOverlaps(MeshHandle m, const Sphere& s) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, s); });
  }
  bool doOverlaps(MeshHandle m, const Aabb& b) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, b); });
  }
  bool doOverlaps(MeshHandle m, const Obb& b) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, b); });
  }
  bool doOverlaps(MeshHandle m, const Plane& p) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, p); });
  }
  bool doOverlaps(MeshHandle m, const Triangle& q) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, q); });
  }
  bool doOverlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) override {
    const PlacedSimplices pa(mesh(a), ta), pb(mesh(b), tb);
    for (std::size_t i = 0; i < pa.simplices.size(); ++i) {
      for (std::size_t j = 0; j < pb.simplices.size(); ++j) {
        if (!CGAL::do_overlap(pa.boxes[i], pb.boxes[j])) continue;
        const bool hit = std::visit([](const auto& x, const auto& y) { return CGAL::do_intersect(x, y); },
                                    pa.simplices[i], pb.simplices[j]);
        if (hit) return true;
      }
    }
    return false;
  }

 private:
  template <class Test>
  bool anyTriangle(MeshHandle m, const Test& test) const {
    const Mesh& mesh = this->mesh(m);
    for (std::uint32_t i = 0; i < mesh.triangleCount(); ++i)
      if (test(mesh.triangle(i))) return true;
    return false;
  }
};

}  // namespace

std::unique_ptr<CollisionWorld> makeExactWorld() { return std::make_unique<ExactWorld>(); }

}  // namespace crux::exact
