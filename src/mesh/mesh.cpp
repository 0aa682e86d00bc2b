#include <crux/mesh/mesh.hpp>

#include "bvh_build.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <limits>
#include <sstream>
#include <unordered_set>

namespace crux {
namespace {

/// Vertex and triangle counts must fit the 32-bit indices of TriangleIndices and the BVH.
constexpr std::size_t kMaxMeshElements = std::numeric_limits<std::uint32_t>::max();

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return os.str();
}

void requireFiniteVertices(const std::vector<Vec3>& vertices, const std::string& name) {
  for (std::size_t i = 0; i < vertices.size(); ++i)
    if (!vertices[i].allFinite())
      throw InvalidInput(name + ": vertex " + std::to_string(i) + " has a non-finite coordinate: " + str(vertices[i]));
}

// ---- exact collinearity -------------------------------------------------------------------
// A triangle has zero area iff the cross product (b-a)×(c-a) is exactly zero. Each component
// expands into six products of input coordinates, e.g. for z:
//   bx·cy - bx·ay - ax·cy - by·cx + by·ax + ay·cx   (the ax·ay terms cancel),
// and each product is exactly the sum of two doubles (TwoProduct with fma). Whether those twelve
// doubles sum to zero is decided exactly by Shewchuk's Grow-Expansion with zero elimination
// ("Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates", 1997):
// the expansion is empty iff the sum is zero. A forward error bound filters the common case.
// Exact for every float input, and for double inputs whose non-zero magnitudes lie in
// [2^-480, 2^480] (so no product under- or overflows).

/// Bound on |fl(Σ fl(p_k)) - Σ p_k| / Σ|fl(p_k)| for six products summed in double: the true
/// bound is about 7u (u = 2^-53); 16u leaves room for the rounding of Σ|p_k| itself.
constexpr Wide kCrossFilterRelativeBound = Wide(16) * std::numeric_limits<Wide>::epsilon() / 2;

/// Exactly: is the sum of the `n` (<= 12) doubles zero? (Grow-Expansion, zero components dropped.)
bool sumIsExactlyZero(const Wide* terms, int n) {
  Wide expansion[12];
  int size = 0;
  for (int i = 0; i < n; ++i) {
    Wide q = terms[i];
    int kept = 0;
    for (int j = 0; j < size; ++j) {
      const Wide s = q + expansion[j];  // TwoSum(q, e_j) = s + err exactly
      const Wide bVirtual = s - q;
      const Wide aVirtual = s - bVirtual;
      const Wide err = (q - aVirtual) + (expansion[j] - bVirtual);
      q = s;
      if (err != 0) expansion[kept++] = err;
    }
    if (q != 0) expansion[kept++] = q;
    size = kept;
  }
  return size == 0;
}

/// Exactly: is component `w` of (b-a)×(c-a) zero? (u, v) are the other axes in cyclic order.
bool crossComponentIsZero(const WVec3& a, const WVec3& b, const WVec3& c, int w) {
  const int u = (w + 1) % 3, v = (w + 2) % 3;
  const Wide f[6][2] = {{b[u], c[v]}, {-b[u], a[v]}, {-a[u], c[v]}, {-b[v], c[u]}, {b[v], a[u]}, {a[v], c[u]}};
  Wide products[6];
  Wide sum = 0, magnitude = 0;
  for (int k = 0; k < 6; ++k) {
    products[k] = f[k][0] * f[k][1];
    sum += products[k];
    magnitude += std::abs(products[k]);
  }
  if (std::abs(sum) > kCrossFilterRelativeBound * magnitude) return false;
  Wide terms[12];
  for (int k = 0; k < 6; ++k) {
    terms[2 * k] = products[k];
    terms[2 * k + 1] = std::fma(f[k][0], f[k][1], -products[k]);  // exact rounding error
  }
  return sumIsExactlyZero(terms, 12);
}

/// Exact zero-area test: collinear or repeated corners.
bool hasZeroArea(const Vec3& a, const Vec3& b, const Vec3& c) {
  const WVec3 wa = wide(a), wb = wide(b), wc = wide(c);
  return crossComponentIsZero(wa, wb, wc, 0) && crossComponentIsZero(wa, wb, wc, 1) &&
         crossComponentIsZero(wa, wb, wc, 2);
}

struct SortedTriangleHash {
  std::size_t operator()(const TriangleIndices& t) const {
    std::uint64_t h = t[0];
    h = h * 0x9E3779B97F4A7C15ull ^ t[1];
    h = h * 0x9E3779B97F4A7C15ull ^ t[2];
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

/// A process-wide counter for Mesh::geometryId (never 0).
std::uint64_t nextGeometryId() {
  static std::atomic<std::uint64_t> counter{0};
  return counter.fetch_add(1, std::memory_order_relaxed) + 1;
}

}  // namespace

Mesh::Mesh(std::vector<Vec3> vertices, std::vector<TriangleIndices> triangles, std::string name,
           const BvhBuildOptions& options)
    : vertices_(std::move(vertices)), triangles_(std::move(triangles)), name_(std::move(name)) {
  if (triangles_.empty()) throw InvalidInput(name_ + ": mesh has no triangles");
  if (vertices_.empty())
    throw InvalidInput(name_ + ": mesh has no vertices (but " + std::to_string(triangles_.size()) + " triangles)");
  if (vertices_.size() > kMaxMeshElements)
    throw InvalidInput(name_ + ": mesh has " + std::to_string(vertices_.size()) + " vertices; at most " +
                       std::to_string(kMaxMeshElements) + " are supported");
  if (triangles_.size() > kMaxMeshElements)
    throw InvalidInput(name_ + ": mesh has " + std::to_string(triangles_.size()) + " triangles; at most " +
                       std::to_string(kMaxMeshElements) + " are supported");
  requireFiniteVertices(vertices_, name_);
  const std::size_t n = vertices_.size();
  for (std::size_t i = 0; i < triangles_.size(); ++i)
    for (const std::uint32_t index : triangles_[i])
      if (index >= n)
        throw InvalidInput(name_ + ": triangle " + std::to_string(i) + " has vertex index " + std::to_string(index) +
                           ", out of range (the mesh has " + std::to_string(n) + " vertices)");
  vertices_.shrink_to_fit();
  triangles_.shrink_to_fit();

  const auto start = std::chrono::steady_clock::now();
  try {
    bvh_ = detail::buildTriangleWideBvh(vertices_, triangles_, options);
  } catch (const InvalidInput& e) {  // bad build options
    throw InvalidInput(name_ + ": " + e.what());
  }
  geometryId_ = nextGeometryId();
  slotTriangles_.resize(triangles_.size());
  for (std::size_t k = 0; k < triangles_.size(); ++k) slotTriangles_[k] = triangles_[bvh_.primIndices[k]];
  updateBounds();
  buildSeconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Mesh::setVertices(std::vector<Vec3> vertices) {
  if (vertices.size() != vertices_.size())
    throw InvalidInput(name_ + ": setVertices got " + std::to_string(vertices.size()) + " vertices, the mesh has " +
                       std::to_string(vertices_.size()));
  requireFiniteVertices(vertices, name_);
  vertices_ = std::move(vertices);
  refitWideBvhSlots(bvh_, [&](std::uint32_t k) { return crux::bounds(slotTriangle(k)); });
  updateBounds();
  geometryId_ = nextGeometryId();
}

void Mesh::updateBounds() {
  bounds_ = wideSubtreeBounds(bvh_, 0);
  scale_ = std::max(bounds_.min.cwiseAbs().maxCoeff(), bounds_.max.cwiseAbs().maxCoeff());
}

void requireCurrentGeometry(const Mesh& mesh, std::uint64_t builtFrom, const char* object) {
  if (builtFrom != mesh.geometryId())
    throw InvalidInput(std::string(object) + " is stale for mesh \"" + mesh.name() +
                       "\": it was built from another mesh, or from this one before its last setVertices; rebuild it");
}

std::vector<Vec3> Mesh::slotCorners() const {
  std::vector<Vec3> out(3 * slotTriangles_.size());
  for (std::size_t k = 0; k < slotTriangles_.size(); ++k)
    for (int i = 0; i < 3; ++i) out[3 * k + i] = vertices_[slotTriangles_[k][i]];
  return out;
}

MeshStats Mesh::stats() const {
  MeshStats s;
  s.triangles = triangles_.size();
  s.vertices = vertices_.size();
  s.bounds = bounds();

  std::unordered_set<TriangleIndices, SortedTriangleHash> seen;
  seen.reserve(triangles_.size());
  for (const TriangleIndices& t : triangles_) {
    if (hasZeroArea(vertices_[t[0]], vertices_[t[1]], vertices_[t[2]])) ++s.degenerateTriangles;
    TriangleIndices sorted = t;
    std::sort(sorted.begin(), sorted.end());
    if (!seen.insert(sorted).second) ++s.duplicateTriangles;
  }
  s.edges = closedness(*this);
  return s;
}

std::size_t Mesh::memoryBytes() const {
  return vertices_.capacity() * sizeof(Vec3) + (triangles_.capacity() + slotTriangles_.capacity()) * sizeof(TriangleIndices) +
         bvh_.memoryBytes();
}

}  // namespace crux
