#pragma once
/// @file bullet_crux.hpp  What the Bullet examples share: conversions between Bullet's and crux's
/// vectors, transforms and convex shapes, a static mesh held in both forms, a CPU clock, and the
/// command-line options and exit codes both take.

#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_contact.hpp>
#include <crux/mesh/mesh_query_data.hpp>
#include <crux/mesh/mesh_volume.hpp>

#include <btBulletCollisionCommon.h>

#include <crux/mesh/mesh_io.hpp>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <time.h>
#include <utility>
#include <vector>

namespace crux_example {

constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;
constexpr int kExitSkip = 77;  ///< CTest SKIP_RETURN_CODE: the mesh data is missing

/// The options every example takes (--bodies, --steps, --seed, --mesh) and its usage line; the
/// example reads its own options first and hands the rest to read().
struct CommonOptions {
  const char* program = "";
  const char* usageText = "";
  std::string mesh;
  int bodies = 1;
  int steps = 1;
  unsigned seed = 1;

  /// Prints "<program>: <problem>" and the usage to stderr and exits with kExitUsage.
  [[noreturn]] void usage(const std::string& problem) const {
    std::fprintf(stderr, "%s: %s\n%s", program, problem.c_str(), usageText);
    std::exit(kExitUsage);
  }
  /// `text` as an integer in [1, 1000000], else usage().
  int positiveInt(const std::string& flag, const std::string& text) const {
    char* end = nullptr;
    const long v = std::strtol(text.c_str(), &end, 10);
    if (end == text.c_str() || *end != '\0' || v < 1 || v > 1000000)
      usage(flag + ": expected an integer in [1, 1000000]");
    return int(v);
  }
  /// Reads one of the common options; an unknown flag is a usage error.
  void read(const std::string& flag, const std::string& value) {
    if (flag == "--bodies") bodies = positiveInt(flag, value);
    else if (flag == "--steps") steps = positiveInt(flag, value);
    else if (flag == "--seed") seed = unsigned(positiveInt(flag, value));
    else if (flag == "--mesh") mesh = value;
    else usage("unknown option '" + flag + "'");
  }
};

/// crux::loadMesh(path), or nothing after printing "<program>: skipped: cannot load the mesh"
/// (the caller exits with kExitSkip).
inline std::optional<crux::Mesh> loadMeshOrSkip(const std::string& path, const char* program) {
  try {
    return crux::loadMesh(path);
  } catch (const std::exception& e) {
    std::printf("%s: skipped: cannot load the mesh: %s\n", program, e.what());
    return std::nullopt;
  }
}

inline btVector3 toBt(const crux::Vec3& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); }
inline crux::Vec3 toCrux(const btVector3& v) {
  return crux::Vec3(crux::Real(v.x()), crux::Real(v.y()), crux::Real(v.z()));
}
inline btTransform toBt(const crux::Transform& t) {
  const crux::Quat& q = t.rotation;
  return btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
                     toBt(t.translation));
}
inline crux::Transform toCrux(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  crux::Transform out;
  out.rotation = crux::Quat(crux::Real(q.w()), crux::Real(q.x()), crux::Real(q.y()), crux::Real(q.z())).normalized();
  out.translation = toCrux(t.getOrigin());
  return out;
}

/// The crux view (body frame) of a Bullet convex shape with the same geometry: the sphere's and
/// capsule's radii, the box's full half extents (Bullet's margin lies inside them). False for
/// shape types the examples do not hand to crux.
inline bool toCruxShape(const btCollisionShape& shape, crux::ConvexShape& out) {
  switch (shape.getShapeType()) {
    case SPHERE_SHAPE_PROXYTYPE:
      out = crux::Sphere{crux::Vec3::Zero(), crux::Real(static_cast<const btSphereShape&>(shape).getRadius())};
      return true;
    case BOX_SHAPE_PROXYTYPE: {
      crux::Obb box;
      box.half = toCrux(static_cast<const btBoxShape&>(shape).getHalfExtentsWithMargin());
      out = box;
      return true;
    }
    case CAPSULE_SHAPE_PROXYTYPE: {
      const auto& capsule = static_cast<const btCapsuleShape&>(shape);
      crux::Vec3 axis = crux::Vec3::Zero();
      axis[capsule.getUpAxis()] = crux::Real(capsule.getHalfHeight());
      out = crux::Capsule{-axis, axis, crux::Real(capsule.getRadius())};
      return true;
    }
    default:
      return false;
  }
}

/// CPU time of the calling thread (POSIX CLOCK_THREAD_CPUTIME_ID): robust on a loaded machine.
inline double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// A static triangle mesh in both forms: the crux Mesh (+ its query data for contacts, + volume
/// view when closed)
/// and the arrays behind Bullet's btBvhTriangleMeshShape, with the same vertices.
struct StaticMesh {
  std::unique_ptr<crux::Mesh> mesh;
  std::unique_ptr<crux::MeshQueryData> queryData;  ///< contacts part (internal-edge correction)
  std::unique_ptr<crux::MeshVolume> volume;  ///< null when the mesh is not closed
  std::vector<int> indices;
  std::vector<btScalar> positions;
};

/// Triangle orientation of makeStaticMesh's output.
enum class Winding { Keep, Reverse };

/// `loaded` scaled uniformly by `scale` about its bounding-box centre, which goes to `origin`,
/// its coordinates rounded to btScalar so that crux and Bullet collide with the very same
/// triangles (in the double build too, where crux::Real is double and Bullet float). With
/// Winding::Reverse every triangle is turned inside out (for bodies touching a closed mesh from
/// inside: Bullet's internal-edge utility is single-sided). crux's queries do not depend on the
/// winding.
inline StaticMesh makeStaticMesh(const crux::Mesh& loaded, double scale, Winding winding,
                                 const crux::Vec3& origin = crux::Vec3::Zero()) {
  using crux::Real;
  using crux::Vec3;
  StaticMesh out;
  const Vec3 centre = (loaded.bounds().min + loaded.bounds().max) / Real(2);
  std::vector<Vec3> vertices;
  vertices.reserve(loaded.vertexCount());
  for (const Vec3& v : loaded.vertices())
    vertices.push_back(((v - centre) * Real(scale) + origin).cast<btScalar>().cast<Real>());
  out.positions.reserve(3 * vertices.size());
  for (const Vec3& v : vertices)
    for (int i = 0; i < 3; ++i) out.positions.push_back(btScalar(v[i]));
  std::vector<crux::TriangleIndices> triangles;
  triangles.reserve(loaded.triangleCount());
  for (const crux::TriangleIndices& t : loaded.triangles())
    triangles.push_back(winding == Winding::Reverse ? crux::TriangleIndices{t[0], t[2], t[1]} : t);
  out.indices.reserve(3 * triangles.size());
  for (const crux::TriangleIndices& t : triangles)
    for (int i = 0; i < 3; ++i) out.indices.push_back(int(t[i]));
  out.mesh = std::make_unique<crux::Mesh>(std::move(vertices), std::move(triangles), loaded.name());
  out.queryData = std::make_unique<crux::MeshQueryData>(*out.mesh, crux::MeshQueryParts::Contacts);
  if (out.mesh->stats().closed()) out.volume = std::make_unique<crux::MeshVolume>(*out.mesh);
  return out;
}

/// Bullet's striding view of a StaticMesh's arrays, for a btBvhTriangleMeshShape. Bullet reads
/// them in place (the mesh must outlive the view) and does not write them.
inline std::unique_ptr<btTriangleIndexVertexArray> bulletTriangles(const StaticMesh& m) {
  auto& positions = const_cast<std::vector<btScalar>&>(m.positions);
  auto& indices = const_cast<std::vector<int>&>(m.indices);
  return std::make_unique<btTriangleIndexVertexArray>(int(indices.size() / 3), indices.data(), int(3 * sizeof(int)),
                                                      int(positions.size() / 3), positions.data(),
                                                      int(3 * sizeof(btScalar)));
}

}  // namespace crux_example
