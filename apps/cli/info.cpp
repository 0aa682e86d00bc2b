#include "cli/info.hpp"
#include "cli/mesh_ops.hpp"

#include "cli/batch.hpp"

#include <crux/error.hpp>
#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_io.hpp>

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <utility>

namespace crux::cli {
namespace {

/// Everything reported for one loaded file.
struct MeshReport {
  std::string path;
  MeshStats stats;
  double loadSeconds = 0;
  double buildSeconds = 0;
  BvhShape bvh;
  std::size_t memoryBytes = 0;
  double bytesPerTriangle = 0;
  MeshMemoryEstimate estimate;  ///< what the loader checks against available memory first
};

MeshReport report(const std::string& path, const Mesh& mesh, double loadSeconds) {
  MeshReport r;
  r.path = path;
  r.stats = mesh.stats();
  r.loadSeconds = loadSeconds;
  r.buildSeconds = mesh.buildSeconds();
  r.bvh = bvhShape(mesh.bvh());
  r.memoryBytes = mesh.memoryBytes();
  r.bytesPerTriangle = double(r.memoryBytes) / double(std::max<std::size_t>(1, r.stats.triangles));
  r.estimate = estimateMeshMemory(r.stats.vertices, r.stats.triangles);
  return r;
}

Answer vec3Json(const Vec3& v) { return Answer::array({double(v.x()), double(v.y()), double(v.z())}); }

Answer toJson(const MeshReport& r) {
  Answer j = Answer::object();
  j["path"] = r.path;
  j["triangles"] = r.stats.triangles;
  j["vertices"] = r.stats.vertices;
  j["bounds"] = Answer::object({{"min", vec3Json(r.stats.bounds.min)}, {"max", vec3Json(r.stats.bounds.max)}});
  j["degenerate_triangles"] = r.stats.degenerateTriangles;
  j["duplicate_triangles"] = r.stats.duplicateTriangles;
  j["non_manifold_edges"] = r.stats.edges.nonManifoldEdges;
  j["boundary_edges"] = r.stats.edges.boundaryEdges;
  j["inconsistent_edges"] = r.stats.edges.inconsistentEdges;
  j["closed"] = r.stats.closed();
  j["load_seconds"] = r.loadSeconds;
  j["bvh_build_seconds"] = r.buildSeconds;
  Answer bvh = Answer::object();
  bvh["nodes"] = r.bvh.nodes;
  bvh["leaves"] = r.bvh.leaves;
  bvh["mean_lanes"] = r.bvh.meanLanes;
  bvh["depth"] = r.bvh.depth;
  bvh["mean_leaf_depth"] = r.bvh.meanLeafDepth;
  bvh["mean_leaf_size"] = r.bvh.meanLeafSize;
  bvh["max_leaf_size"] = r.bvh.maxLeafSize;
  j["bvh"] = std::move(bvh);
  j["memory_bytes"] = r.memoryBytes;
  j["bytes_per_triangle"] = r.bytesPerTriangle;
  j["estimated_mesh_bytes"] = r.estimate.meshBytes;
  j["estimated_peak_bytes"] = r.estimate.peakBytes;
  return j;
}

std::string text(const Vec3& v) {
  std::ostringstream os;
  os << std::setprecision(std::numeric_limits<Real>::max_digits10) << "[" << v.x() << ", " << v.y() << ", "
     << v.z() << "]";
  return os.str();
}

void writeText(std::ostream& out, const MeshReport& r) {
  const MeshStats& s = r.stats;
  const auto row = [&out](const char* label) -> std::ostream& {
    return out << "  " << std::left << std::setw(22) << label << std::right;
  };
  out << r.path << '\n';
  row("triangles") << s.triangles << '\n';
  row("vertices") << s.vertices << '\n';
  row("bounds") << text(s.bounds.min) << " .. " << text(s.bounds.max) << '\n';
  row("degenerate triangles") << s.degenerateTriangles << '\n';
  row("duplicate triangles") << s.duplicateTriangles << '\n';
  row("non-manifold edges") << s.edges.nonManifoldEdges << '\n';
  row("boundary edges") << s.edges.boundaryEdges << '\n';
  row("inconsistent edges") << s.edges.inconsistentEdges << '\n';
  row("closed") << (s.closed() ? "yes" : "no") << '\n';
  out << std::fixed << std::setprecision(6);
  row("load time") << r.loadSeconds << " s (BVH build " << r.buildSeconds << " s)\n";
  out << std::setprecision(2);
  row("BVH") << r.bvh.nodes << " 4-wide nodes (" << r.bvh.meanLanes << " lanes used on average), " << r.bvh.leaves
             << " leaves, depth " << r.bvh.depth
             << " (mean leaf depth " << r.bvh.meanLeafDepth << "), leaf size mean " << r.bvh.meanLeafSize
             << " max " << r.bvh.maxLeafSize << '\n';
  row("memory") << r.memoryBytes << " bytes (" << r.bytesPerTriangle << " bytes/triangle)\n";
  row("memory estimate") << r.estimate.meshBytes << " bytes built, " << r.estimate.peakBytes
                         << " bytes peak while building (checked before a load: docs/limits.md)\n";
  out.unsetf(std::ios::floatfield);
  out << std::setprecision(6);
}

}  // namespace

BvhShape bvhShape(const WideBvh& bvh) {
  BvhShape shape;
  shape.nodes = bvh.nodes.size();
  if (bvh.nodes.empty()) return shape;
  std::size_t leafDepthSum = 0, leafSizeSum = 0, lanes = 0;
  std::vector<std::pair<std::uint32_t, std::size_t>> stack = {{0u, 0u}};  // node, depth
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    const WideBvhNode& node = bvh.nodes[index];
    for (int i = 0; i < 4; ++i) {
      if (!node.used(i)) continue;
      ++lanes;
      if (node.count[i] == 0) {
        stack.emplace_back(node.child[i], depth + 1);
        continue;
      }
      ++shape.leaves;
      shape.depth = std::max(shape.depth, depth);
      shape.maxLeafSize = std::max<std::size_t>(shape.maxLeafSize, node.count[i]);
      leafDepthSum += depth;
      leafSizeSum += node.count[i];
    }
  }
  shape.meanLanes = double(lanes) / double(shape.nodes);
  shape.meanLeafDepth = double(leafDepthSum) / double(shape.leaves);
  shape.meanLeafSize = double(leafSizeSum) / double(shape.leaves);
  return shape;
}

int runInfo(const std::vector<std::string>& paths, const InfoOptions& options, std::ostream& out,
            std::ostream& err) {
  int status = 0;
  bool first = true;
  for (const std::string& path : paths) {
    try {
      const auto start = std::chrono::steady_clock::now();
      const Mesh mesh = loadMeshFile(path, options.cruxExecutable);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const MeshReport r = report(path, mesh, seconds);
      if (options.json) {
        out << toJson(r).dump(-1, ' ', false, Answer::error_handler_t::replace) << '\n';
      } else {
        if (!first) out << '\n';
        writeText(out, r);
      }
      first = false;
    } catch (const std::exception& e) {
      // loadMesh's InvalidInput messages start with the path; anything else gets it prepended.
      const std::string message =
          dynamic_cast<const InvalidInput*>(&e) ? std::string(e.what()) : path + ": " + e.what();
      err << "crux info: " << message << '\n';
      if (options.json) {
        Answer j = Answer::object();
        j["path"] = path;
        j["error"] = message;
        out << j.dump(-1, ' ', false, Answer::error_handler_t::replace) << '\n';
      }
      status = 1;
    }
  }
  out.flush();
  return status;
}

}  // namespace crux::cli
