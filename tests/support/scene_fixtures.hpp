#pragma once
/// @file scene_fixtures.hpp  Seeded scenes, query shapes and bitwise comparisons shared by the
/// scene batch and concurrency tests (tests/scene/test_scene_batch.cpp,
/// tests/scene/test_concurrent_queries.cpp).

#include <crux/scene/scene_batch.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace crux::test {

/// A bumpy UV sphere (radius 1 ± 0.2) of about 2·rings·segments triangles.
inline std::shared_ptr<const Mesh> bumpySphere(int rings, int segments) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (int i = 0; i <= rings; ++i) {
    const double theta = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * M_PI * j / segments;
      const double r = 1 + 0.2 * std::sin(5 * theta) * std::cos(3 * phi);
      v.emplace_back(Real(r * std::sin(theta) * std::cos(phi)), Real(r * std::sin(theta) * std::sin(phi)),
                     Real(r * std::cos(theta)));
    }
  }
  auto at = [&](int i, int j) { return std::uint32_t(i * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return std::make_shared<const Mesh>(std::move(v), std::move(t), "bumpy sphere");
}

inline Quat randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Vector4d q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return Quat(Real(q[0]), Real(q[1]), Real(q[2]), Real(q[3]));
}

inline Transform randomPose(std::mt19937_64& rng, double range) {
  std::uniform_real_distribution<double> u(-range, range);
  Transform t;
  t.rotation = randomRotation(rng);
  t.translation = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
  return t;
}

/// A scene of `roots` families (a root with two children and a grandchild) scattered in
/// [-8, 8]^3, then every root moved once (so the hierarchy's world transforms were recomputed).
inline void populate(Scene& scene, const std::shared_ptr<const Mesh>& mesh, int roots, std::mt19937_64& rng) {
  std::vector<ModelId> rootIds;
  for (int r = 0; r < roots; ++r) {
    const ModelId root = scene.add(mesh, randomPose(rng, 8));
    const ModelId a = scene.add(mesh, randomPose(rng, 2), root);
    scene.add(mesh, randomPose(rng, 2), root);
    scene.add(mesh, randomPose(rng, 2), a);
    rootIds.push_back(root);
  }
  for (const ModelId root : rootIds) scene.setTransform(root, randomPose(rng, 8));
}

/// Rays from a sphere of radius 20 towards random points of [-10, 10]^3.
inline std::vector<Ray> sceneRays(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-10, 10);
  std::normal_distribution<double> g(0, 1);
  std::vector<Ray> rays(n);
  for (Ray& r : rays) {
    r.origin = (20 * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized()).cast<Real>();
    r.dir = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))) - r.origin;
  }
  return rays;
}

inline std::vector<Sphere> sceneSpheres(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-10, 10), r(0.1, 2);
  std::vector<Sphere> out(n);
  for (Sphere& s : out) s = {Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))), Real(r(rng))};
  return out;
}

inline std::vector<Aabb> sceneBoxes(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-10, 10), e(0.1, 2);
  std::vector<Aabb> out(n);
  for (Aabb& b : out) {
    const Vec3 c(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    const Vec3 h(Real(e(rng)), Real(e(rng)), Real(e(rng)));
    b = {c - h, c + h};
  }
  return out;
}

inline std::vector<Obb> sceneObbs(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-10, 10), e(0.1, 2);
  std::vector<Obb> out(n);
  for (Obb& b : out) {
    b.center = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    b.half = Vec3(Real(e(rng)), Real(e(rng)), Real(e(rng)));
    b.axes = randomRotation(rng).toRotationMatrix();
  }
  return out;
}

inline bool sameBits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), 3 * sizeof(Real)) == 0; }
inline bool sameHit(const std::optional<MeshRayHit>& a, const std::optional<MeshRayHit>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return std::memcmp(&a->t, &b->t, sizeof(Real)) == 0 && sameBits(a->point, b->point) &&
         sameBits(a->normal, b->normal) && a->triangle == b->triangle;
}
inline bool sameHit(const std::optional<SceneRayHit>& a, const std::optional<SceneRayHit>& b) {
  if (a.has_value() != b.has_value()) return false;
  return !a || (a->model == b->model && sameHit(std::optional<MeshRayHit>(a->hit), std::optional<MeshRayHit>(b->hit)));
}

inline std::string str(Real x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", double(x));
  return buf;
}
inline std::string str(const Vec3& p) { return "(" + str(p.x()) + ", " + str(p.y()) + ", " + str(p.z()) + ")"; }
inline std::string str(const Ray& r) { return "Ray{" + str(r.origin) + ", " + str(r.dir) + "}"; }
inline std::string str(const Sphere& s) { return "Sphere{" + str(s.center) + ", " + str(s.radius) + "}"; }
inline std::string str(const Aabb& b) { return "Aabb{" + str(b.min) + ", " + str(b.max) + "}"; }
inline std::string str(const Obb& b) {
  return "Obb{" + str(b.center) + ", " + str(b.half) + ", x " + str(Vec3(b.axes.col(0))) + ", y " +
         str(Vec3(b.axes.col(1))) + "}";
}

}  // namespace crux::test
