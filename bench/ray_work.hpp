#pragma once
/// @file ray_work.hpp  The work crux does per ray (RayQueryCounters), for the benches' notes and
/// JSON: where a ray's time goes, beside its time. Embree exposes no such counters; its
/// instructions per ray come from `crux report --callgrind`.

#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_query.hpp>

#include "peers/bench_types.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>

namespace crux::bench {

/// Per-ray means over a query set.
struct RayWork {
  double nodes = 0;           ///< wide BVH nodes entered
  double triangles = 0;       ///< triangles tested (float filter)
  double certifiedShare = 0;  ///< share of tested triangles settled as certified crossings
  double exactShare = 0;      ///< share of tested triangles that took the exact path

  std::string text() const {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "%.1f nodes, %.1f triangles per ray; %.1f%% of the triangles certified by the float filter, "
                  "%.2f%% on the exact path",
                  nodes, triangles, 100 * certifiedShare, 100 * exactShare);
    return buf;
  }
};

/// Casts every query (closest hit, or any hit) once with counters on.
inline RayWork measureRayWork(const crux::Mesh& mesh, const RayQuery* q, std::size_t n, bool any) {
  crux::RayQueryCounters c;
  crux::RayQueryOptions o;
  o.counters = &c;
  for (std::size_t i = 0; i < n; ++i) {
    const crux::Ray ray{crux::Vec3(crux::Real(q[i].origin[0]), crux::Real(q[i].origin[1]), crux::Real(q[i].origin[2])),
                        crux::Vec3(crux::Real(q[i].dir[0]), crux::Real(q[i].dir[1]), crux::Real(q[i].dir[2]))};
    if (any) crux::raycastAny(mesh, ray, o);
    else crux::raycastClosest(mesh, ray, o);
  }
  const double rays = double(std::max<std::size_t>(n, 1)), tested = double(std::max<std::uint64_t>(c.triangles, 1));
  return {double(c.nodes) / rays, double(c.triangles) / rays, double(c.certified) / tested, double(c.exactPath) / tested};
}

}  // namespace crux::bench
