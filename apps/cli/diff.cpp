/// @file diff.cpp  `crux diff`: running cases on the backends, classifying the answers against
/// the exact arbiter, shrinking, and the run's summary (docs/diff.md).

#include "cli/diff.hpp"
#include "cli/peer_worker.hpp"

#include <crux/error.hpp>
#include <crux/geometry/axis_aligned.hpp>
#include <crux/geometry/cast.hpp>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/contact.hpp>
#include <crux/geometry/predicates.hpp>
#include <crux/geometry/triangle_distance.hpp>
#include <crux/mesh/mesh.hpp>

#include <Eigen/Geometry>


#if __has_include(<world_factory.hpp>)
#include <world_factory.hpp>
#define CRUX_DIFF_HAVE_ORACLE 1
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <ostream>
#include <set>
#include <sstream>

namespace crux::cli {
namespace {

using J = Answer;
using V = std::array<double, 3>;

bool hasError(const Answer& a) { return a.contains("error"); }
std::string errorText(const Answer& a) { return hasError(a) ? a["error"].get<std::string>() : std::string(); }
bool startsWith(const std::string& s, std::string_view prefix) { return s.compare(0, prefix.size(), prefix) == 0; }

bool isRayOp(std::string_view op) {
  return op == "ray_triangle" || op == "mesh_ray" || op == "model_ray" || op == "scene_ray";
}
bool isRayOrSegmentOp(std::string_view op) {
  return isRayOp(op) || op == "segment_triangle" || op == "mesh_segment" || op == "model_segment";
}

V readV(const J& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }
double maxDiff(const J& a, const J& b) {
  double d = 0;
  for (std::size_t i = 0; i < 3; ++i) d = std::max(d, std::fabs(a[i].get<double>() - b[i].get<double>()));
  return d;
}

/// How two answers to the same query differ.
enum class Difference { None, Boolean, Numeric, List, Shape };

// ---- the narrow-phase ops: distance, contacts, mesh_distance, model_distance ------------

/// Distances, depths and witnesses of the narrow-phase ops are compared within kNarrowRelative·s
/// (s: the case's magnitude) on top of the backends' declared tolerances: the narrow phase's bound, 1e-6
/// relative, in double builds; in float builds inputs and outputs are rounded to float, so 64
/// float ulps (7.6e-6) relative (docs/narrowphase.md "Accuracy").
constexpr double kNarrowRelative =
    sizeof(Real) == sizeof(double) ? 1e-6 : 64 * double(std::numeric_limits<float>::epsilon());

/// Relative slack on a contact's depth for crux's face-snapped manifold normal: 1 − cos 2°
/// (docs/narrowphase.md "Contact manifolds": a face within 2° of the contact normal becomes the
/// manifold normal).
constexpr double kManifoldAngleSlack = 1 - double(kContactFaceAngleCos);

bool isNarrowOp(std::string_view op) {
  return op == "distance" || op == "contacts" || op == "mesh_distance" || op == "model_distance";
}

/// mesh_distance and model_distance: two meshes (placed by transforms / by models), answer
/// `found` (within the optional max) and the distance with its witness points.
bool isMeshPairDistance(std::string_view op) { return op == "mesh_distance" || op == "model_distance"; }

/// The boolean part of a narrow-phase answer: contacts: any point within the margin;
/// mesh_distance, model_distance: found (within max); distance: touching or overlapping
/// (distance <= 0).
bool narrowVerdict(std::string_view op, const J& a) {
  if (op == "contacts") return a.contains("contacts") && !a["contacts"].empty();
  if (isMeshPairDistance(op)) return a.value("found", false);
  return a.contains("distance") && a["distance"].get<double>() <= 0;
}

/// The number of a narrow-phase answer: the distance, or the deepest contact's depth.
double narrowNumber(std::string_view op, const J& a) {
  if (op != "contacts") return a.contains("distance") ? a["distance"].get<double>() : 0;
  double deepest = -std::numeric_limits<double>::infinity();
  for (const auto& k : a["contacts"]) deepest = std::max(deepest, k["depth"].get<double>());
  return deepest;
}

/// Compares narrow-phase answers: the verdict exactly (contacts, mesh/model_distance), the distance
/// or deepest depth within `tolerance`. Witness points are checked separately (witnessProblem).
Difference compareNarrow(std::string_view op, const J& got, const J& exact, double tolerance) {
  const char* key = op == "contacts" ? "contacts" : isMeshPairDistance(op) ? "found" : "distance";
  if (!got.contains(key)) return Difference::Shape;
  if (op != "distance" && narrowVerdict(op, got) != narrowVerdict(op, exact)) return Difference::Boolean;
  if (op != "distance" && !narrowVerdict(op, exact)) return Difference::None;
  if (op != "contacts" && (!got.contains("point_a") || !got.contains("point_b"))) return Difference::Shape;
  // Contacts: exact's depth is the minimum penetration depth (per triangle for meshes); a
  // manifold measures its points along its own normal (crux: a face normal within 2° of the
  // contact normal, internal-edge contacts re-measured along the face normal; Bullet: per
  // triangle), and the overlap along any direction is at least the minimum. So the deepest
  // depth may exceed exact's but must not fall short of it.
  // A separated (speculative) contact measured along a face normal up to 2° off the contact
  // normal (kContactFaceAngleCos) may read a separation up to a factor 1/cos 2° larger: that
  // relative slack, kManifoldAngleSlack, is allowed on top of the tolerance.
  if (op == "contacts") {
    const double want = narrowNumber(op, exact);
    return narrowNumber(op, got) < want - tolerance - kManifoldAngleSlack * std::fabs(want) ? Difference::Numeric
                                                                                         : Difference::None;
  }
  return std::fabs(narrowNumber(op, got) - narrowNumber(op, exact)) > tolerance ? Difference::Numeric
                                                                                : Difference::None;
}

bool isCastOp(std::string_view op) { return op == "cast" || op == "model_cast" || op == "scene_cast"; }

/// The length of a linear cast's motion (0 for a rigid one, whose query has "end" instead).
double motionLength(const J& query) {
  if (!query.contains("motion")) return 0;
  const V m = readV(query["motion"]);
  return std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
}

/// How far apart two casts' times of impact are, as a distance along the motion (at least 1
/// unit long: a short motion's t is compared as a fraction).
double castTimeGap(const J& query, const J& got, const J& exact) {
  return std::fabs(got["t"].get<double>() - exact["t"].get<double>()) * std::max(motionLength(query), 1.0);
}

/// Compares cast answers: the hit exactly; when both give a time of impact (exact gives none for
/// spheres and capsules, FCL no points), t as a distance along the motion within `tolerance`.
Difference compareCast(const J& query, const J& got, const J& exact, double tolerance) {
  if (!got.contains("hit") || !got["hit"].is_boolean()) return Difference::Shape;
  if (got["hit"] != exact["hit"]) return Difference::Boolean;
  if (!exact["hit"].get<bool>() || !exact.contains("t") || !exact["t"].is_number()) return Difference::None;
  if (!got.contains("t")) return Difference::Shape;
  if (!got["t"].is_number()) return Difference::None;  // hit alone
  return castTimeGap(query, got, exact) > tolerance ? Difference::Numeric : Difference::None;
}

/// Compares answers (neither an error). Booleans and lists exactly (a bounds-only scene query
/// may return a superset: broad phases pad bounds), numbers within `tolerance`.
Difference compareAnswers(std::string_view op, const J& query, const J& got, const J& exact, double tolerance) {
  if (isNarrowOp(op)) return compareNarrow(op, got, exact, tolerance);
  if (isCastOp(op)) return compareCast(query, got, exact, tolerance);
  if (exact.contains("hit")) {
    if (!got.contains("hit") || !got["hit"].is_boolean()) return Difference::Shape;
    if (got["hit"] != exact["hit"]) return Difference::Boolean;
    if (isRayOp(op) && exact["hit"].get<bool>()) {
      if (!got.contains("t") || !got.contains("point")) return Difference::Shape;
      if (std::fabs(got["t"].get<double>() - exact["t"].get<double>()) > tolerance ||
          maxDiff(got["point"], exact["point"]) > tolerance)
        return Difference::Numeric;
    }
    return Difference::None;
  }
  if (exact.contains("point")) {
    if (!got.contains("point")) return Difference::Shape;
    return maxDiff(got["point"], exact["point"]) > tolerance ? Difference::Numeric : Difference::None;
  }
  for (const char* key : {"models", "pairs"}) {
    if (!exact.contains(key)) continue;
    if (!got.contains(key)) return Difference::Shape;
    if (got[key] == exact[key]) return Difference::None;
    if (query.value("bounds", false)) {
      std::set<J> have(got[key].begin(), got[key].end());
      for (const auto& e : exact[key])
        if (!have.count(e)) return Difference::List;
      return Difference::None;
    }
    return Difference::List;
  }
  return got == exact ? Difference::None : Difference::Shape;
}

/// The 26 non-zero offsets of {-τ,0,τ}³, axis-aligned ones first; with `dense`, then the 6
/// axis and 8 diagonal directions again at τ/4, τ/16, ... τ/4¹⁰ (a contact window thinner than τ,
/// such as a triangle almost parallel to a plane, is missed by the coarse lattice alone).
std::vector<Vec3d> probeOffsets(double tau, bool dense) {
  std::vector<Vec3d> out;
  for (int pass = 1; pass <= 3; ++pass)
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z)
          if (std::abs(x) + std::abs(y) + std::abs(z) == pass) out.push_back(Vec3d(x, y, z) * tau);
  if (dense) {
    const std::size_t coarse = out.size();
    for (double f = 0.25; f > 1e-6; f *= 0.25)
      for (std::size_t i = 0; i < coarse; ++i)
        if (out[i].cwiseAbs().maxCoeff() > 0 && (out[i].cwiseAbs().minCoeff() > 0 || (out[i].array() != 0).count() == 1))
          out.push_back(out[i] * f);
  }
  return out;
}

/// Whether the exact answer changes when the query shape moves by up to τ per axis; with
/// `matchGot`, whether some moved case's exact answer equals `got` (within `numTol`).
bool probeFlips(const DiffCase& c, const J& query, const J& exact, const J& got, double tau, double numTol,
                const std::function<Answer(const DiffCase&)>& probeExact, bool matchGot) {
  if (!(tau > 0)) return false;
  std::set<J> listUnion, listCommon;
  const char* listKey = exact.contains("models") ? "models" : exact.contains("pairs") ? "pairs" : nullptr;
  bool first = true;
  if (listKey) {
    for (const auto& e : exact[listKey]) listCommon.insert(e);
    listUnion = listCommon;
    first = false;
  }
  // scene_pairs: move a model of the first pair on which the answers differ (the last model
  // added may be in no such pair)
  std::string mover;
  if (c.op == "scene_pairs" && got.contains("pairs") && exact.contains("pairs")) {
    const std::set<J> g(got["pairs"].begin(), got["pairs"].end()), e(exact["pairs"].begin(), exact["pairs"].end());
    for (const auto* from : {&e, &g}) {
      const std::set<J>& other = from == &e ? g : e;
      for (const J& pair : *from)
        if (mover.empty() && !other.count(pair) && pair.is_array() && pair.size() == 2 && pair[1].is_string())
          mover = pair[1].get<std::string>();
    }
  }
  for (const Vec3d& off : probeOffsets(tau, !c.sharedSetup)) {
    const auto moved = translatedCase(c, off, mover);
    if (!moved) return false;
    const Answer p = probeExact(*moved);
    if (hasError(p)) continue;
    if (matchGot) {
      if (compareAnswers(c.op, query, got, p, numTol) == Difference::None) return true;
    } else if (isNarrowOp(c.op) ? narrowVerdict(c.op, p) != narrowVerdict(c.op, exact)
                                : compareAnswers(c.op, query, p, exact, 0) != Difference::None) {
      return true;
    }
    if (listKey && p.contains(listKey)) {
      std::set<J> s(p[listKey].begin(), p[listKey].end());
      for (const auto& e : s) listUnion.insert(e);
      std::set<J> common;
      for (const auto& e : listCommon)
        if (s.count(e)) common.insert(e);
      listCommon = std::move(common);
    }
  }
  if (listKey && matchGot && !first && got.contains(listKey)) {
    // every element on which got and exact differ is unstable under the moves
    std::set<J> g(got[listKey].begin(), got[listKey].end()), e(exact[listKey].begin(), exact[listKey].end());
    for (const auto& x : g)
      if (!e.count(x) && (!listUnion.count(x) || listCommon.count(x))) return false;
    for (const auto& x : e)
      if (!g.count(x) && listCommon.count(x)) return false;
    return true;
  }
  return false;
}

// ---- facts about a case used by the cause rules --------------------------------------------------

/// Triangles of a case in the query's frame: the query's own triangle fields and, for mesh
/// queries without transforms, the triangles of the meshes defined by setup lines.
/// With `allMeshes`, the triangles of every mesh line (in their own frames).
std::vector<std::array<V, 3>> caseTriangles(const DiffCase& c, const J& query, bool allMeshes = false) {
  std::vector<std::array<V, 3>> out;
  for (const char* key : {"triangle", "a", "b"})
    if (query.contains(key) && query[key].is_array() && query[key].size() == 3)
      out.push_back({readV(query[key][0]), readV(query[key][1]), readV(query[key][2])});
  for (const char* key : {"a", "b"})  // triangle operands of the narrow-phase ops and casts (own frame)
    if (query.contains(key) && query[key].is_object() && query[key].contains("triangle")) {
      const J& t = query[key]["triangle"];
      out.push_back({readV(t[0]), readV(t[1]), readV(t[2])});
    }
  if (allMeshes || (startsWith(c.op, "mesh_") && c.op != "mesh_mesh")) {
    for (const auto& line : c.setup) {
      const J m = J::parse(line, nullptr, false);
      if (!m.is_object() || m.value("op", "") != "mesh") continue;
      if (!allMeshes && m.value("name", "") != query.value("mesh", "")) continue;
      const auto& vs = m["vertices"];
      for (const auto& t : m["triangles"])
        out.push_back({readV(vs[t[0].get<std::size_t>()]), readV(vs[t[1].get<std::size_t>()]),
                       readV(vs[t[2].get<std::size_t>()])});
    }
  }
  return out;
}

long double orient(const std::array<V, 3>& t, const V& p) {
  long double m[3][3];
  for (std::size_t i = 0; i < 3; ++i) {
    m[0][i] = (long double)t[1][i] - t[0][i];
    m[1][i] = (long double)t[2][i] - t[0][i];
    m[2][i] = (long double)p[i] - t[0][i];
  }
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}
bool degenerate(const std::array<V, 3>& t) {
  const V u = {t[1][0] - t[0][0], t[1][1] - t[0][1], t[1][2] - t[0][2]};
  const V v = {t[2][0] - t[0][0], t[2][1] - t[0][1], t[2][2] - t[0][2]};
  return (long double)u[1] * v[2] - (long double)u[2] * v[1] == 0 &&
         (long double)u[2] * v[0] - (long double)u[0] * v[2] == 0 &&
         (long double)u[0] * v[1] - (long double)u[1] * v[0] == 0;
}

/// The smallest height of a triangle (twice its area over its longest edge; 0 when degenerate).
double smallestHeight(const std::array<V, 3>& t) {
  const Vec3d a(t[0][0], t[0][1], t[0][2]), b(t[1][0], t[1][1], t[1][2]), c(t[2][0], t[2][1], t[2][2]);
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  return longest > 0 ? (b - a).cross(c - a).norm() / longest : 0;
}

/// x rounded to Real as the backends read it, through a volatile: every rule rounds through this
/// helper. GCC 12.2's SLP vectoriser drops a plain double(float(x)) on some lanes: in
///   std::array<double, 3> f(std::array<double, 3> v) { for (double& x : v) x = double(float(x)); return v; }
/// at -O2 or -O3 (with or without -frounding-math; not with -fno-tree-slp-vectorize) only v[2]
/// comes back rounded, v[0] and v[1] are copied unchanged. The float replay's `asReal` is that
/// loop, and with a plain cast DiffClassify.BulletFloatRayTriangle (seed 98765 case 56163)
/// fails: the ray's origin stays unrounded.
double roundedToReal(double x) {
  volatile Real r = Real(x);
  return double(r);
}

/// The gap between the shapes of a triangle_plane or triangle_triangle case as the backends see
/// them (coordinates in Real): the triangle's distance to the plane (0 when its corners are on
/// both sides), or the triangles' distance (closestPoints); NaN for other ops.
double caseGap(const DiffCase& c, const J& query) {
  auto triangle = [](const J& t) {
    return Triangle{Vec3(Real(t[0][0].get<double>()), Real(t[0][1].get<double>()), Real(t[0][2].get<double>())),
                    Vec3(Real(t[1][0].get<double>()), Real(t[1][1].get<double>()), Real(t[1][2].get<double>())),
                    Vec3(Real(t[2][0].get<double>()), Real(t[2][1].get<double>()), Real(t[2][2].get<double>()))};
  };
  if (c.op == "triangle_plane" && query.contains("triangle") && query.contains("plane")) {
    const Triangle t = triangle(query["triangle"]);
    const V nv = readV(query["plane"]["normal"]);
    const Vec3d n = Vec3d(roundedToReal(nv[0]), roundedToReal(nv[1]), roundedToReal(nv[2]));
    const double d = roundedToReal(query["plane"]["d"].get<double>()), len = n.norm();
    if (!(len > 0)) return NAN;
    double lo = INFINITY, hi = -INFINITY;
    for (const Vec3& p : {t.a, t.b, t.c}) {
      const double side = (n.dot(p.cast<double>()) - d) / len;
      lo = std::min(lo, side), hi = std::max(hi, side);
    }
    return lo <= 0 && hi >= 0 ? 0 : std::min(std::fabs(lo), std::fabs(hi));
  }
  if (c.op == "triangle_triangle" && query.contains("a") && query.contains("b"))
    return double(closestPoints(triangle(query["a"]), triangle(query["b"])).distance);
  return NAN;
}

/// A ray origin or segment endpoint lying exactly on the plane of a (non-degenerate) triangle.
bool endpointOnPlane(const J& query, const std::vector<std::array<V, 3>>& tris) {
  std::vector<V> points;
  if (query.contains("ray")) points.push_back(readV(query["ray"]["origin"]));
  if (query.contains("segment")) {
    points.push_back(readV(query["segment"]["start"]));
    points.push_back(readV(query["segment"]["end"]));
  }
  for (const auto& t : tris)
    if (!degenerate(t))
      for (const V& p : points)
        if (orient(t, p) == 0) return true;
  return false;
}

/// Bullet's raycast edge tolerance (btTriangleRaycastCallback::processTriangle): a crossing point
/// counts as inside an edge when cross(v_i − p, v_j − p)·n >= −1e-4·|n|², i.e. its barycentric
/// coordinate opposite that edge is at least −1e-4.
constexpr long double kBulletRayEdgeTolerance = 1e-4L;

/// The smallest barycentric coordinate of the point where a ray or segment crosses the plane of
/// a (non-degenerate) triangle (long double, on the coordinates rounded to Real as the backends
/// read them: a segment through a corner in double may pass 7.5e-8 outside an edge in float);
/// none when it does not cross within the ray or segment, or lies parallel to the plane.
std::optional<long double> crossingBarycentric(const J& query, const std::array<V, 3>& t) {
  using L = long double;
  const auto real = [](double x) { return L(roundedToReal(x)); };
  std::array<L, 3> o{}, d{};
  L tMax = 0;
  if (query.contains("ray")) {
    const V a = readV(query["ray"]["origin"]), b = readV(query["ray"]["dir"]);
    for (std::size_t i = 0; i < 3; ++i) o[i] = real(a[i]), d[i] = real(b[i]);
    tMax = std::numeric_limits<L>::infinity();
  } else if (query.contains("segment")) {
    const V a = readV(query["segment"]["start"]), b = readV(query["segment"]["end"]);
    for (std::size_t i = 0; i < 3; ++i) o[i] = real(a[i]), d[i] = real(b[i]) - real(a[i]);
    tMax = 1;
  } else {
    return std::nullopt;
  }
  using P = std::array<L, 3>;
  auto sub = [](const P& a, const P& b) { return P{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  auto cross = [](const P& a, const P& b) {
    return P{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  auto dot = [](const P& a, const P& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  if (degenerate(t)) return std::nullopt;
  P v[3];
  for (std::size_t i = 0; i < 3; ++i) v[i] = {real(t[i][0]), real(t[i][1]), real(t[i][2])};
  const P n = cross(sub(v[1], v[0]), sub(v[2], v[0]));
  const L nn = dot(n, n), nd = dot(n, d);
  if (nd == 0) return std::nullopt;
  const L u = dot(n, sub(v[0], o)) / nd;
  if (!(u >= 0 && u <= tMax)) return std::nullopt;
  const P p = {o[0] + u * d[0], o[1] + u * d[1], o[2] + u * d[2]};
  L lowest = 1;
  for (std::size_t i = 0; i < 3; ++i)
    lowest = std::min(lowest, dot(cross(sub(v[(i + 1) % 3], p), sub(v[(i + 2) % 3], p)), n) / nn);
  return lowest;
}

/// A ray or segment that crosses the plane of a (non-degenerate) triangle outside it, but by at
/// most Bullet's edge tolerance: every barycentric coordinate of the crossing point >= −1e-4
/// (crossingBarycentric). Called where exact misses: a crossing that long double puts on an edge
/// or a corner (its least barycentric within 1e-12 of 0) lies outside by less than long double
/// resolves, when the segment's ends lie strictly on either side of the plane (orient3dExact; so
/// exact's miss is the crossing's, not an end's) — seed 98765 case 757699: a segment whose start
/// is 1.4e-45 (the least float) off z = 0, crossing 7e-46 beside a corner.
bool withinFattenedEdges(const J& query, const std::vector<std::array<V, 3>>& tris) {
  const auto strictlyAcross = [&](const std::array<V, 3>& t) {
    if (!query.contains("segment")) return false;
    const auto real = [](const V& v) {
      return WVec3(Wide(roundedToReal(v[0])), Wide(roundedToReal(v[1])), Wide(roundedToReal(v[2])));
    };
    const int sa = predicates::orient3dExact(real(t[0]), real(t[1]), real(t[2]), real(readV(query["segment"]["start"])));
    const int sb = predicates::orient3dExact(real(t[0]), real(t[1]), real(t[2]), real(readV(query["segment"]["end"])));
    return sa * sb < 0;
  };
  for (const auto& t : tris) {
    const auto lowest = crossingBarycentric(query, t);
    if (!lowest || *lowest < -kBulletRayEdgeTolerance) continue;
    if (*lowest < 0 || (*lowest <= 1e-12L && strictlyAcross(t))) return true;
  }
  return false;
}

/// Where the ray o + u·d (coordinates rounded to Real) meets the triangle's plane ahead of its
/// origin: u = |orient(o)| / |n·d| when o's exact side `originSide` (orient3dExact) and the sign
/// of n·d say it does (0 for an origin on the plane), magnitudes in long double; none otherwise.
/// The side decides the crossing, not the rounded orient(o), which for an origin within rounding
/// of the plane may have the other sign (seed 98765 case 269579).
std::optional<long double> rayCrossingAhead(const std::array<V, 3>& t, const V& o, const V& d, int originSide,
                                            long double* normalDotDir = nullptr) {
  using L = long double;
  const auto at = [](const V& v, std::size_t i) { return L(roundedToReal(v[i])); };
  L e1[3], e2[3], od[3], dd[3];
  for (std::size_t i = 0; i < 3; ++i)
    e1[i] = at(t[1], i) - at(t[0], i), e2[i] = at(t[2], i) - at(t[0], i), od[i] = at(o, i) - at(t[0], i),
    dd[i] = at(d, i);
  const L n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  // orient3d(a, b, c, p) = n·(p − a) with n = (b − a)×(c − a)
  const L no = n[0] * od[0] + n[1] * od[1] + n[2] * od[2], nd = n[0] * dd[0] + n[1] * dd[1] + n[2] * dd[2];
  if (normalDotDir) *normalDotDir = nd;
  if (originSide == 0) return L(0);
  if (nd == 0 || (nd > 0) == (originSide > 0)) return std::nullopt;
  return std::fabs(no) / std::fabs(nd);
}

/// The side of the triangle's plane (orient3d's sign) of the ray's point o + s·d: o's exact side
/// `originSide` unless the ray crosses the plane before s (rayCrossingAhead).
int rayFarSide(const std::array<V, 3>& t, const V& o, const V& d, double s, int originSide) {
  long double nd = 0;
  const auto u = rayCrossingAhead(t, o, d, originSide, &nd);
  if (!u || *u >= s) return originSide;
  return (nd > 0) - (nd < 0);
}

/// The smallest barycentric coordinate of the ray's point o + u·d in the triangle (long double,
/// coordinates rounded to Real).
long double barycentricAt(const std::array<V, 3>& t, const V& o, const V& d, long double u) {
  using L = long double;
  using P = std::array<L, 3>;
  const auto lp = [](const V& v) { return P{L(roundedToReal(v[0])), L(roundedToReal(v[1])), L(roundedToReal(v[2]))}; };
  const auto sub = [](const P& a, const P& b) { return P{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  const auto cross = [](const P& a, const P& b) {
    return P{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  const auto dot = [](const P& a, const P& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const P v[3] = {lp(t[0]), lp(t[1]), lp(t[2])}, po = lp(o), pd = lp(d);
  const P n = cross(sub(v[1], v[0]), sub(v[2], v[0]));
  const P p = {po[0] + u * pd[0], po[1] + u * pd[1], po[2] + u * pd[2]};
  L lowest = 1;
  for (std::size_t i = 0; i < 3; ++i)
    lowest = std::min(lowest, dot(cross(sub(v[(i + 1) % 3], p), sub(v[(i + 2) % 3], p)), n) / dot(n, n));
  return lowest;
}

/// What a float replay of Bullet's raycast finds wrong: nothing, the side of an endpoint
/// (`float-plane-side`), or the crossing point (`float-crossing-point`).
enum class BulletFloatRay { None, Side, Crossing };

/// A segment or ray that Bullet hits through float arithmetic:
/// btTriangleRaycastCallback::processTriangle, replayed in float on the segment and triangle as
/// Bullet holds them (coordinates rounded to float, its operation order), reports the triangle
/// (dist_a·dist_b < 0, the crossing before the end and within the 1e-4 edge tolerance), and
/// - `Side`: the sign of dist_a or dist_b differs from the exact side of that endpoint
///   (orient3dExact on the endpoint as the exact backend reads it, Real; for a ray's far end, on
///   the float point Bullet holds). Only an endpoint within float rounding of the plane gets the
///   wrong sign (seed 9001 case 3523: an end 1.95e-7 short of the plane in a float build, Bullet's
///   dist_b −3.7e-4 with |n| = 358; case 2641: a segment lying within 5e-8 of the plane, dist_a
///   and dist_b ±4.8e-7; seed 98765 cases 56163 and 77247: rays lying within rounding of the
///   plane, transformed family);
/// - `Crossing`: the sides are right, but the exact crossing of the ray or segment
///   (crossingBarycentric) lies beyond the edge tolerance (a barycentric below −1e-4): for a ray
///   grazing the plane, Bullet's float crossing moves along the ray by the float rounding of its
///   far end and of dist_a/(dist_a − dist_b), relative to dist_a − dist_b, times the segment's
///   length (seed 98765 case 16898: a ray 3.5e-4 rad off the plane, dist_a −3.3e-3 and dist_b
///   5.7e-3 over 10.8 with |n| = 2.4; the crossing's barycentric −1.03e-4 exactly, −8.4e-5 in
///   Bullet's float replay).
/// A segment (no transform) is taken as given; a `ray_triangle` ray as the bullet world casts it:
/// from the origin to origin + L·d̂ (double, then rounded to float), L twice the distance to the
/// farthest corner of the triangle's bounding box.
BulletFloatRay bulletFloatRaycast(std::string_view op, const J& query, const std::vector<std::array<V, 3>>& tris) {
  if (query.contains("transform")) return BulletFloatRay::None;
  using F3 = std::array<float, 3>;
  const auto f3 = [](const V& v) { return F3{float(v[0]), float(v[1]), float(v[2])}; };
  const auto sub = [](const F3& a, const F3& b) { return F3{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  const auto cross = [](const F3& a, const F3& b) {
    return F3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  const auto dot = [](const F3& a, const F3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const auto real = [](const V& v) {
    return WVec3(Wide(roundedToReal(v[0])), Wide(roundedToReal(v[1])), Wide(roundedToReal(v[2])));
  };
  const auto asReal = [](V v) {  // as the backends read it
    for (double& x : v) x = roundedToReal(x);
    return v;
  };
  V start, end, rayDir{};
  double rayReach = 0;  // the far end's parameter along the ray's dir
  bool ray = false;
  if (query.contains("segment")) {
    start = readV(query["segment"]["start"]), end = readV(query["segment"]["end"]);
  } else if (op == "ray_triangle" && query.contains("ray") && tris.size() == 1) {
    ray = true;
    const V raw = readV(query["ray"]["origin"]);
    start = asReal(raw);
    const Vec3d o(start[0], start[1], start[2]);
    const V dr = asReal(readV(query["ray"]["dir"]));
    const Vec3d u = Vec3d(dr[0], dr[1], dr[2]).normalized();
    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const V& c : tris[0]) {
      const V r = asReal(c);
      lo = lo.cwiseMin(Vec3d(r[0], r[1], r[2])), hi = hi.cwiseMax(Vec3d(r[0], r[1], r[2]));
    }
    double far2 = 0;
    for (int k = 0; k < 8; ++k)
      far2 = std::max(far2, (Vec3d((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z()) - o)
                                .squaredNorm());
    const double length = far2 > 0 ? 2 * std::sqrt(far2) : 1.0;
    const Vec3d e = o + length * u;
    rayDir = dr;
    rayReach = length / Vec3d(dr[0], dr[1], dr[2]).norm();
    const F3 ef = {float(e.x()), float(e.y()), float(e.z())};
    end = {double(ef[0]), double(ef[1]), double(ef[2])};
  } else {
    return BulletFloatRay::None;
  }
  const F3 from = f3(start), to = f3(end);
  for (const auto& t : tris) {
    if (degenerate(t)) continue;
    // Bullet's side test and crossing, in its float operation order
    const F3 v0 = f3(t[0]), v1 = f3(t[1]), v2 = f3(t[2]);
    const F3 n = cross(sub(v1, v0), sub(v2, v0));
    const float dist = dot(v0, n);
    const float distA = dot(n, from) - dist, distB = dot(n, to) - dist;
    if (distA * distB >= 0.0f) continue;
    const float fraction = distA / (distA - distB);
    if (!(fraction < 1.0f)) continue;
    const float edgeTolerance = dot(n, n) * -0.0001f;
    const float keep = 1.0f - fraction;
    const F3 point = {keep * from[0] + fraction * to[0], keep * from[1] + fraction * to[1],
                      keep * from[2] + fraction * to[2]};
    const F3 v0p = sub(v0, point), v1p = sub(v1, point), v2p = sub(v2, point);
    if (!(dot(cross(v0p, v1p), n) >= edgeTolerance && dot(cross(v1p, v2p), n) >= edgeTolerance &&
          dot(cross(v2p, v0p), n) >= edgeTolerance))
      continue;
    // an endpoint on the other side (or on the plane) exactly
    const auto sign = [](float x) { return (x > 0) - (x < 0); };
    const int sa = predicates::orient3dExact(real(t[0]), real(t[1]), real(t[2]), real(start));
    const int sb = ray ? rayFarSide(t, start, rayDir, rayReach, sa) : predicates::orient3dExact(real(t[0]), real(t[1]), real(t[2]), real(end));
    if (sa != sign(distA) || sb != sign(distB)) return BulletFloatRay::Side;
    // the sides are right: the exact crossing lies beyond the edge tolerance?
    std::optional<long double> lowest;
    if (ray) {
      if (const auto u = rayCrossingAhead(t, start, rayDir, sa)) lowest = barycentricAt(t, start, rayDir, *u);
    } else {
      lowest = crossingBarycentric(query, t);
    }
    if (lowest && *lowest < -kBulletRayEdgeTolerance) return BulletFloatRay::Crossing;
  }
  return BulletFloatRay::None;
}

/// A triangle operand against a sphere operand whose normal (b − a)×(c − a), computed in float
/// as Bullet does, has |n|² < FLT_EPSILON²: Bullet's SphereTriangleDetector::collide treats such
/// a triangle (twice its area below 1.2e-7, an absolute threshold) as having no normal and
/// reports no contact.
bool sphereTriangleFloatNormalTooSmall(const J& query) {
  const J* triangle = nullptr;
  bool sphere = false;
  for (const char* side : {"a", "b"}) {
    if (!query.contains(side) || !query[side].is_object()) continue;
    if (query[side].contains("triangle")) triangle = &query[side]["triangle"];
    if (query[side].contains("sphere")) sphere = true;
  }
  if (!triangle || !sphere) return false;
  std::array<std::array<float, 3>, 3> v{};
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t k = 0; k < 3; ++k) v[i][k] = float((*triangle)[i][k].get<double>());
  float e1[3], e2[3];
  for (std::size_t k = 0; k < 3; ++k) e1[k] = v[1][k] - v[0][k], e2[k] = v[2][k] - v[0][k];
  const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  const float eps = std::numeric_limits<float>::epsilon();
  return n[0] * n[0] + n[1] * n[1] + n[2] * n[2] < eps * eps;
}

/// The smallest non-zero size across of the query's shapes (sphere diameter, box extents),
/// or +inf.
double smallestShape(const J& query) {
  double m = std::numeric_limits<double>::infinity();
  auto consider = [&](double x) {
    if (x > 0) m = std::min(m, x);
  };
  if (query.contains("sphere")) consider(2 * query["sphere"]["radius"].get<double>());
  if (query.contains("aabb")) {
    const V lo = readV(query["aabb"]["min"]), hi = readV(query["aabb"]["max"]);
    for (std::size_t i = 0; i < 3; ++i) consider(hi[i] - lo[i]);
  }
  if (query.contains("obb")) {
    const V h = readV(query["obb"]["half"]);
    for (std::size_t i = 0; i < 3; ++i) consider(2 * h[i]);
  }
  return m;
}

bool flatShape(const J& query, bool* pointSphere) {
  if (query.contains("sphere") && query["sphere"]["radius"].get<double>() == 0) {
    *pointSphere = true;
    return true;
  }
  if (query.contains("aabb")) {
    const V lo = readV(query["aabb"]["min"]), hi = readV(query["aabb"]["max"]);
    for (std::size_t i = 0; i < 3; ++i)
      if (lo[i] == hi[i]) return true;
  }
  if (query.contains("obb")) {
    const V h = readV(query["obb"]["half"]);
    if (h[0] == 0 || h[1] == 0 || h[2] == 0) return true;
  }
  return false;
}

// ---- witnesses of the narrow-phase ops ------------------------------------------------------------

Vec3d toVec(const J& v) { return Vec3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>()); }

/// A point of an operand's frame to the world and back: R·x + t, from the operand's
/// "transform" (rotation [w, x, y, z], normalised here).
struct Placement {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Vec3d t = Vec3d::Zero();
  explicit Placement(const J* transform) {
    if (!transform || !transform->is_object()) return;
    if (transform->contains("translation")) t = toVec((*transform)["translation"]);
    if (transform->contains("rotation")) {
      const J& q = (*transform)["rotation"];
      r = Eigen::Quaterniond(q[0].get<double>(), q[1].get<double>(), q[2].get<double>(), q[3].get<double>())
              .normalized()
              .toRotationMatrix();
    }
  }
  Vec3d toLocal(const Vec3d& p) const { return r.transpose() * (p - t); }
};

/// Distance from p to the triangle abc (double; crux's Voronoi-region closest point, RTCD 5.1.5).
double triangleGap(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& p) {
  const Triangle t{a.cast<Real>(), b.cast<Real>(), c.cast<Real>()};
  return (closestPoint(t, p.cast<Real>()).cast<double>() - p).norm();
}

/// Whether a `ray_triangle` hit is the exact first hit of the query triangle moved by at most
/// `move` (any direction, real-valued): its t is at least 0, the point o + t·d/|d| lies within
/// `move` of the triangle, the reported point within `tolerance` of it, and the ray crosses the
/// triangle's plane (the line then meets the moved triangle's plane at that point only, so it is
/// the first hit). The check of a grazing ray's t, which is ill-conditioned: a move δ along the
/// normal moves the hit by δ/|cos θ|, so a rounded t may be off by more than τ while the lattice
/// probe, whose moves are representable numbers, cannot reach the sub-ulp move that explains it.
bool rayHitOnMovedTriangle(const J& query, const J& answer, double move, double tolerance) {
  if (!query.contains("triangle") || !query.contains("ray") || !answer.contains("t") || !answer.contains("point"))
    return false;
  const Vec3d a = toVec(query["triangle"][0]), b = toVec(query["triangle"][1]), c = toVec(query["triangle"][2]);
  const Vec3d o = toVec(query["ray"]["origin"]), d = toVec(query["ray"]["dir"]);
  if (!(std::fabs((b - a).cross(c - a).dot(d)) > 0) || !(d.norm() > 0)) return false;
  const double t = answer["t"].get<double>();
  const Vec3d onRay = o + t * d.normalized();
  return t >= 0 && triangleGap(a, b, c, onRay) <= move && (toVec(answer["point"]) - onRay).norm() <= tolerance;
}

/// Meshes a case defines or loads, by name (loaded files cached per path for the run).
const Mesh* caseMesh(const DiffCase& c, const std::string& name, std::vector<std::array<Vec3d, 3>>& inline_) {
  static std::map<std::string, std::shared_ptr<const Mesh>> loaded;
  for (const auto& line : c.setup) {
    const J m = J::parse(line, nullptr, false);
    if (!m.is_object() || m.value("name", "") != name) continue;
    if (m.value("op", "") == "mesh") {
      inline_.clear();
      const auto& vs = m["vertices"];
      for (const auto& t : m["triangles"])
        inline_.push_back({toVec(vs[t[0].get<std::size_t>()]), toVec(vs[t[1].get<std::size_t>()]),
                           toVec(vs[t[2].get<std::size_t>()])});
      return nullptr;
    }
    if (m.value("op", "") == "load_mesh") {
      const std::string path = m.value("path", "");
      auto it = loaded.find(path);
      if (it == loaded.end()) {
        std::shared_ptr<const Mesh> mesh;
        try {
          mesh = std::make_shared<const Mesh>(loadMesh(path));
        } catch (const std::exception&) {
        }
        it = loaded.emplace(path, mesh).first;
      }
      return it->second.get();
    }
  }
  return nullptr;
}

/// Triangle `index` of the case's mesh `name` (an inline or a loaded mesh), in the mesh's frame;
/// none when the mesh or the triangle is unknown.
std::optional<std::array<V, 3>> caseMeshTriangle(const DiffCase& c, const std::string& name, std::size_t index) {
  std::vector<std::array<Vec3d, 3>> inline_;
  const Mesh* mesh = caseMesh(c, name, inline_);
  std::array<Vec3d, 3> t;
  if (mesh && index < mesh->triangleCount()) {
    const Triangle m = mesh->triangle(std::uint32_t(index));
    t = {m.a.cast<double>(), m.b.cast<double>(), m.c.cast<double>()};
  } else if (!mesh && index < inline_.size()) {
    t = inline_[index];
  } else {
    return std::nullopt;
  }
  return std::array<V, 3>{V{t[0].x(), t[0].y(), t[0].z()}, V{t[1].x(), t[1].y(), t[1].z()}, V{t[2].x(), t[2].y(), t[2].z()}};
}

/// rayHitOnMovedTriangle for a `mesh_ray` (no transform: mesh coordinates are world ones) whose
/// answer and exact's hit the same triangle of the mesh: the answer is the exact hit of that
/// triangle moved by at most `move` (found on grazing rays on blob-closed, |cos θ| 7.5e-5 and
/// 5.6e-4, t off by 6.7e-13 and 8e-14 in double builds, were reported crux-wrong for lack of this
/// rule, which `ray_triangle` already had).
bool meshRayHitOnMovedTriangle(const DiffCase& c, const J& query, const J& got, const J& exact, double move,
                               double tolerance) {
  if (!query.contains("mesh") || !query["mesh"].is_string() || !got.contains("triangle") || !exact.contains("triangle") ||
      got["triangle"] != exact["triangle"] || !got["triangle"].is_number_unsigned())
    return false;
  const std::size_t index = got["triangle"].get<std::size_t>();
  std::vector<std::array<Vec3d, 3>> inline_;
  const Mesh* mesh = caseMesh(c, query["mesh"].get<std::string>(), inline_);
  std::array<Vec3d, 3> tri;
  if (mesh) {
    if (index >= mesh->triangleCount()) return false;
    const Triangle t = mesh->triangle(std::uint32_t(index));
    tri = {t.a.cast<double>(), t.b.cast<double>(), t.c.cast<double>()};
  } else {
    if (index >= inline_.size()) return false;
    tri = inline_[index];
  }
  J single = query;
  single["triangle"] = J::array();
  for (const Vec3d& v : tri) single["triangle"].push_back({v.x(), v.y(), v.z()});
  return rayHitOnMovedTriangle(single, got, move, tolerance);
}

/// How far the world point p lies outside the operand (0 inside or on it); NaN when the
/// operand kind is not checked (hulls). `meshName`/`transform` describe a mesh operand of
/// mesh_distance.
double gapToOperand(const DiffCase& c, const J& operand, const Vec3d& world) {
  const Placement place(operand.contains("transform") ? &operand["transform"] : nullptr);
  const Vec3d p = place.toLocal(world);
  if (operand.contains("sphere"))
    return std::max(0.0, (p - toVec(operand["sphere"]["center"])).norm() - operand["sphere"]["radius"].get<double>());
  if (operand.contains("box")) {
    const J& b = operand["box"];
    const Vec3d d = p - toVec(b["center"]);
    Vec3d out = Vec3d::Zero();
    for (int i = 0; i < 3; ++i) {
      const Vec3d axis = toVec(b["axes"][std::size_t(i)]).normalized();
      out[i] = std::max(0.0, std::fabs(axis.dot(d)) - b["half"][std::size_t(i)].get<double>());
    }
    return out.norm();
  }
  if (operand.contains("capsule")) {
    const J& k = operand["capsule"];
    const Vec3d a = toVec(k["a"]), b = toVec(k["b"]), ab = b - a;
    const double len2 = ab.squaredNorm();
    const double u = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return std::max(0.0, (p - (a + u * ab)).norm() - k["radius"].get<double>());
  }
  if (operand.contains("triangle")) {
    const J& t = operand["triangle"];
    return triangleGap(toVec(t[0]), toVec(t[1]), toVec(t[2]), p);
  }
  if (operand.contains("mesh")) {
    std::vector<std::array<Vec3d, 3>> tris;
    const Mesh* mesh = caseMesh(c, operand["mesh"].get<std::string>(), tris);
    double best = std::numeric_limits<double>::infinity();
    if (mesh) {
      for (std::uint32_t i = 0; i < mesh->triangleCount(); ++i) {
        const Triangle t = mesh->triangle(i);
        best = std::min(best, triangleGap(t.a.cast<double>(), t.b.cast<double>(), t.c.cast<double>(), p));
      }
    }
    for (const auto& t : tris) best = std::min(best, triangleGap(t[0], t[1], t[2], p));
    return std::isfinite(best) ? best : std::numeric_limits<double>::quiet_NaN();
  }
  return std::numeric_limits<double>::quiet_NaN();  // hull: not checked
}

/// A model's placement in the world as the setup lines give it: its mesh, its world rotation
/// (as a quaternion, and as a matrix: each axis-aligned rotation snapped to its exact signed
/// permutation as crux's model layer does, snapAxisAligned, so a chain of them composes exactly)
/// and translation (double).
struct ModelWorldPose {
  std::string mesh;
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Vec3d t = Vec3d::Zero();
};

/// The world pose of model `name`: parent_world ∘ local, composed in double from add_model,
/// set_transform and set_parent lines (set_parent keeps the world pose). Nothing when the model
/// is not defined.
std::optional<ModelWorldPose> modelWorldPose(const DiffCase& c, const std::string& name) {
  struct ModelLine {
    std::string parent;
    ModelWorldPose local;
  };
  std::map<std::string, ModelLine> models;
  auto readPose = [](const J& tr, std::string mesh) {
    ModelWorldPose p;
    p.mesh = std::move(mesh);
    if (!tr.is_object()) return p;
    if (tr.contains("translation")) p.t = toVec(tr["translation"]);
    if (tr.contains("rotation")) {
      const J& q = tr["rotation"];
      p.q = Eigen::Quaterniond(q[0].get<double>(), q[1].get<double>(), q[2].get<double>(), q[3].get<double>())
                .normalized();
      const Quat read(Real(q[0].get<double>()), Real(q[1].get<double>()), Real(q[2].get<double>()),
                      Real(q[3].get<double>()));
      const std::optional<Quat> snapped = snapAxisAligned(read.normalized());
      p.r = snapped ? Eigen::Matrix3d(signedPermutation(*snapped).cast<double>()) : p.q.toRotationMatrix();
    }
    return p;
  };
  auto compose = [](const ModelWorldPose& a, const ModelWorldPose& b) {  // a ∘ b
    ModelWorldPose p;
    p.mesh = b.mesh;
    p.q = a.q * b.q, p.r = a.r * b.r, p.t = a.r * b.t + a.t;
    return p;
  };
  std::function<ModelWorldPose(const std::string&, int)> world = [&](const std::string& m, int depth) {
    const auto it = models.find(m);
    if (it == models.end() || depth > 64) return ModelWorldPose{};
    if (it->second.parent.empty()) return it->second.local;
    return compose(world(it->second.parent, depth + 1), it->second.local);
  };
  for (const auto& line : c.setup) {
    const J m = J::parse(line, nullptr, false);
    if (!m.is_object()) continue;
    const std::string op = m.value("op", "");
    if (op == "add_model" && m.contains("name") && m["name"].is_string()) {
      ModelLine& d = models[m["name"].get<std::string>()];
      d.parent = m.contains("parent") && m["parent"].is_string() ? m["parent"].get<std::string>() : "";
      d.local = readPose(m.contains("transform") ? m["transform"] : J(), m.value("mesh", ""));
    } else if ((op == "set_transform" || op == "set_parent") && m.contains("model") && m["model"].is_string()) {
      const std::string who = m["model"].get<std::string>();
      const auto it = models.find(who);
      if (it == models.end()) continue;
      if (op == "set_transform") {
        it->second.local = readPose(m.contains("transform") ? m["transform"] : J(), it->second.local.mesh);
      } else {
        const ModelWorldPose w = world(who, 0);
        it->second.parent = m.contains("parent") && m["parent"].is_string() ? m["parent"].get<std::string>() : "";
        const ModelWorldPose p = it->second.parent.empty() ? ModelWorldPose{} : world(it->second.parent, 0);
        ModelWorldPose inverse;
        inverse.q = p.q.conjugate(), inverse.r = p.r.transpose(), inverse.t = -(p.r.transpose() * p.t);
        it->second.local = compose(inverse, w);
      }
    }
  }
  if (!models.count(name)) return std::nullopt;
  return world(name, 0);
}

/// A model's mesh operand as the setup lines place it: {"mesh": its mesh, "transform": its world
/// transform} (modelWorldPose). Null when the model is not defined.
J modelOperand(const DiffCase& c, const std::string& name) {
  const std::optional<ModelWorldPose> w = modelWorldPose(c, name);
  if (!w) return J();
  return J{{"mesh", w->mesh},
           {"transform",
            {{"rotation", {w->q.w(), w->q.x(), w->q.y(), w->q.z()}}, {"translation", {w->t.x(), w->t.y(), w->t.z()}}}}};
}

/// The triangles of model `name` placed in the world by its exactly composed world pose
/// (modelWorldPose: exact for axis-aligned rotations and integer data); empty when unknown.
std::vector<std::array<V, 3>> placedModelTriangles(const DiffCase& c, const std::string& name) {
  std::vector<std::array<V, 3>> out;
  const std::optional<ModelWorldPose> w = modelWorldPose(c, name);
  if (!w) return out;
  std::vector<std::array<Vec3d, 3>> tris;
  if (const Mesh* mesh = caseMesh(c, w->mesh, tris)) {
    for (std::uint32_t i = 0; i < mesh->triangleCount(); ++i) {
      const Triangle t = mesh->triangle(i);
      tris.push_back({t.a.cast<double>(), t.b.cast<double>(), t.c.cast<double>()});
    }
  }
  for (const auto& t : tris) {
    std::array<V, 3> placed;
    for (std::size_t k = 0; k < 3; ++k) {
      const Vec3d p = w->r * t[k] + w->t;
      placed[k] = {p.x(), p.y(), p.z()};
    }
    out.push_back(placed);
  }
  return out;
}

/// The triangles, placed in the world, of the models a model_ray / model_segment / scene_ray
/// case is about: the query's model; for scene_ray the models named by either answer.
std::vector<std::array<V, 3>> rayModelTriangles(const DiffCase& c, const J& query, const J& got, const J& exact) {
  std::set<std::string> names;
  if ((c.op == "model_ray" || c.op == "model_segment") && query.contains("model") && query["model"].is_string())
    names.insert(query["model"].get<std::string>());
  if (c.op == "scene_ray")
    for (const J* a : {&got, &exact})
      if (a->contains("model") && (*a)["model"].is_string()) names.insert((*a)["model"].get<std::string>());
  std::vector<std::array<V, 3>> out;
  for (const std::string& name : names)
    for (const auto& t : placedModelTriangles(c, name)) out.push_back(t);
  return out;
}

/// `scene_ray`: the model exact hits first is culled by Bullet's broad phase. btCollisionWorld::
/// addCollisionObject gives a model's proxy its shape's world AABB unpadded (updateSingleAabb,
/// after a set_transform, pads it by the contact breaking threshold), and btDbvt's ray walk
/// (btRayAabb2) takes a zero direction component as 1/BT_LARGE_FLOAT: along that axis
/// tmax = (max − o)·1e18, and the test wants tmax > 0. A ray lying in the plane of the box's
/// upper face, or outside it (rounding), is culled; exact hits the model on that face (seed 98765
/// case 70040: a quarter-turned model whose edge lies at z = 2, a ray at z = 2; Bullet's
/// model_ray on the same model hits). The box is replayed in float as Bullet computes it: the
/// mesh's local AABB, btMatrix3x3::setRotation of the float quaternion, btTriangleMeshShape::getAabb
/// (centre ± |basis|·half extents). Top-level models placed by add_model only.
bool bulletBroadphaseCullsModel(const DiffCase& c, const J& query, const J& got, const J& exact) {
  if (c.op != "scene_ray" || !exact.value("hit", false) || !exact.contains("model") || !exact["model"].is_string() ||
      !query.contains("ray"))
    return false;
  const std::string name = exact["model"].get<std::string>();
  if (got.value("hit", false) && got.value("model", "") == name) return false;
  J add;
  for (const auto& line : c.setup) {
    const J m = J::parse(line, nullptr, false);
    if (!m.is_object()) continue;
    if (m.value("op", "") == "set_transform" || m.value("op", "") == "set_parent") return false;
    if (m.value("op", "") == "add_model" && m.value("name", "") == name) add = m;
  }
  if (add.is_null() || add.contains("parent") || !add["mesh"].is_string()) return false;
  std::vector<std::array<Vec3d, 3>> tris;
  if (const Mesh* mesh = caseMesh(c, add["mesh"].get<std::string>(), tris))
    for (std::uint32_t i = 0; i < mesh->triangleCount(); ++i) {
      const Triangle t = mesh->triangle(i);
      tris.push_back({t.a.cast<double>(), t.b.cast<double>(), t.c.cast<double>()});
    }
  if (tris.empty()) return false;
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const auto& t : tris)
    for (const Vec3d& v : t)
      for (int i = 0; i < 3; ++i) lo[i] = std::min(lo[i], float(v[i])), hi[i] = std::max(hi[i], float(v[i]));
  // the pose as the bullet world gets it: crux's (Real) quaternion normalised in double, to float
  Eigen::Quaterniond qd = Eigen::Quaterniond::Identity();
  float origin[3] = {0, 0, 0};
  if (add.contains("transform") && add["transform"].is_object()) {
    const J& tr = add["transform"];
    if (tr.contains("rotation")) {
      const J& q = tr["rotation"];
      qd = Eigen::Quaterniond(roundedToReal(q[0].get<double>()), roundedToReal(q[1].get<double>()),
                              roundedToReal(q[2].get<double>()), roundedToReal(q[3].get<double>()))
               .normalized();
    }
    if (tr.contains("translation"))
      for (std::size_t i = 0; i < 3; ++i) origin[i] = float(roundedToReal(tr["translation"][i].get<double>()));
  }
  const float x = float(qd.x()), y = float(qd.y()), z = float(qd.z()), w = float(qd.w());
  // btMatrix3x3::setRotation
  const float d = x * x + y * y + z * z + w * w, sc = 2.0f / d;
  const float xs = x * sc, ys = y * sc, zs = z * sc;
  const float wx = w * xs, wy = w * ys, wz = w * zs, xx = x * xs, xy = x * ys, xz = x * zs, yy = y * ys, yz = y * zs,
              zz = z * zs;
  const float basis[3][3] = {{1.0f - (yy + zz), xy - wz, xz + wy},
                             {xy + wz, 1.0f - (xx + zz), yz - wx},
                             {xz - wy, yz + wx, 1.0f - (xx + yy)}};
  // btTriangleMeshShape::getAabb (margin 0)
  const float half[3] = {0.5f * (hi[0] - lo[0]), 0.5f * (hi[1] - lo[1]), 0.5f * (hi[2] - lo[2])};
  const float centre[3] = {0.5f * (hi[0] + lo[0]), 0.5f * (hi[1] + lo[1]), 0.5f * (hi[2] + lo[2])};
  const V o = readV(query["ray"]["origin"]), dir = readV(query["ray"]["dir"]);
  for (int i = 0; i < 3; ++i) {
    if (roundedToReal(dir[std::size_t(i)]) != 0) continue;
    const float c0 = basis[i][0] * centre[0] + basis[i][1] * centre[1] + basis[i][2] * centre[2] + origin[i];
    const float e = half[0] * std::fabs(basis[i][0]) + half[1] * std::fabs(basis[i][1]) + half[2] * std::fabs(basis[i][2]);
    const float oi = float(roundedToReal(o[std::size_t(i)]));
    // tmax = (max − o)·1e18 must be > 0; tmin = (min − o)·1e18 must stay below the ray's length
    if (c0 + e <= oi || c0 - e > oi) return true;
  }
  return false;
}

/// Checks the witness of a distance / mesh_distance / model_distance answer: point_a on A and point_b on B
/// (within `tolerance` of the shape; for a mesh, of its surface), and |point_a − point_b| =
/// |distance|. Returns "" when it holds, else which part fails; sets *onSphere when the point
/// off its shape belongs to a sphere operand.
std::string witnessProblem(const DiffCase& c, const J& query, const J& answer, double tolerance, bool* onSphere) {
  if (c.op == "contacts" || !answer.contains("point_a") || !answer.contains("point_b")) return "";
  if (isMeshPairDistance(c.op) && !answer.value("found", false)) return "";
  const Vec3d pa = toVec(answer["point_a"]), pb = toVec(answer["point_b"]);
  const double d = answer["distance"].get<double>();
  std::ostringstream out;
  out << std::setprecision(17);
  if (std::fabs((pa - pb).norm() - std::fabs(d)) > tolerance)
    out << "|point_a - point_b| = " << (pa - pb).norm() << " but distance " << d << "; ";
  for (const char* side : {"a", "b"}) {
    J operand;
    if (c.op == "mesh_distance") {
      operand = J{{"mesh", query[side]}};
      const std::string tk = std::string("transform_") + side;
      if (query.contains(tk)) operand["transform"] = query[tk];
    } else if (c.op == "model_distance") {
      operand = query[side].is_string() ? modelOperand(c, query[side].get<std::string>()) : J();
      if (operand.is_null()) continue;
    } else {
      operand = query[side];
    }
    const double gap = gapToOperand(c, operand, side[0] == 'a' ? pa : pb);
    if (gap > tolerance) {
      out << "point_" << side << " is " << gap << " off operand " << side << "; ";
      if (operand.contains("sphere")) *onSphere = true;
    }
  }
  return out.str();
}

/// The core points of a box, hull, triangle, sphere or capsule operand (world coordinates, under
/// its `transform`) and its rounding radius: the polytopes' corners (radius 0); a sphere's centre
/// or a capsule's segment ends, with the radius (libccd and Bullet take them as core ⊕ ball).
/// Empty for other operands.
std::vector<Vec3d> corePoints(const J& operand, double* radius) {
  const Placement place(operand.contains("transform") ? &operand["transform"] : nullptr);
  std::vector<Vec3d> corners;
  *radius = 0;
  if (operand.contains("box")) {
    const J& b = operand["box"];
    for (int k = 0; k < 8; ++k) {
      Vec3d p = toVec(b["center"]);
      for (std::size_t i = 0; i < 3; ++i)
        p += ((k >> i) & 1 ? 1.0 : -1.0) * b["half"][i].get<double>() * toVec(b["axes"][i]).normalized();
      corners.push_back(place.r * p + place.t);
    }
  } else if (operand.contains("hull") || operand.contains("triangle")) {
    for (const auto& p : operand.contains("hull") ? operand["hull"]["points"] : operand["triangle"])
      corners.push_back(place.r * toVec(p) + place.t);
  } else if (operand.contains("sphere") || operand.contains("capsule")) {
    const J& r = operand.contains("sphere") ? operand["sphere"] : operand["capsule"];
    if (operand.contains("sphere")) {
      corners.push_back(place.r * toVec(r["center"]) + place.t);
    } else {
      corners.push_back(place.r * toVec(r["a"]) + place.t);
      corners.push_back(place.r * toVec(r["b"]) + place.t);
    }
    *radius = r["radius"].get<double>();
  }
  return corners;
}

/// The points a support function of a box, hull, triangle, sphere or capsule operand (world
/// coordinates, under its `transform`) may return along `dir`: for the polytopes, the vertices
/// whose support value is within `tie` of the largest; for a sphere, centre + r·dir̂; for a capsule,
/// the end (both ends within `tie`) + r·dir̂, as libccd's supportSphere and supportCap compute
/// them. Empty for other operands.
std::vector<Vec3d> supportPoints(const J& operand, const Vec3d& dir, double tie) {
  double radius = 0;
  const std::vector<Vec3d> corners = corePoints(operand, &radius);
  const Vec3d rounding = radius > 0 ? Vec3d(radius * dir.normalized()) : Vec3d::Zero();  // r·dir̂ of a sphere or capsule
  double best = -std::numeric_limits<double>::infinity();
  for (const Vec3d& p : corners) best = std::max(best, p.dot(dir));
  std::vector<Vec3d> out;
  for (const Vec3d& p : corners)
    if (p.dot(dir) >= best - tie) out.push_back(p + rounding);
  return out;
}

/// A `distance` operand as libccd sees it in FCL's GJK: the operand itself, or for a mesh
/// operand the triangle the peer names (`triangle_a` / `triangle_b`): FCL measures a BVHModel
/// against a shape triangle by triangle, each by the same GJK (shapeTriangleDistance), and
/// reports the least. Null when the mesh or the triangle is unknown.
J gjkOperand(const DiffCase& c, const J& operand, const J& got, const char* triangleKey) {
  if (!operand.contains("mesh")) return operand;
  if (!operand["mesh"].is_string() || !got.contains(triangleKey) || !got[triangleKey].is_number_integer() ||
      got[triangleKey].get<long long>() < 0)
    return nullptr;
  const auto t = caseMeshTriangle(c, operand["mesh"].get<std::string>(), got[triangleKey].get<std::size_t>());
  if (!t) return nullptr;
  J triangle = J::array();
  for (const V& v : *t) triangle.push_back({v[0], v[1], v[2]});
  J out{{"triangle", triangle}};
  if (operand.contains("transform")) out["transform"] = operand["transform"];
  return out;
}

/// FCL's `distance` of separated convex shapes (box, hull, triangle, sphere, capsule: FCL's
/// signed-distance request runs libccd's GJK for every shape pair, its sphere–sphere and
/// sphere–capsule formulas being used for unsigned requests only; a mesh is measured triangle by
/// triangle by the same GJK, shapeTriangleDistance) stopped early by libccd's GJK: its answer
/// v = point_a − point_b (|v| its distance) has a support point w = s_A(−v) − s_B(v) of the
/// Minkowski difference with |w| = |v| within `tau` though w·v̂ < |v| − tau (GJK had not
/// converged). FCL 0.7's `_ccdDist` (gjk_libccd-inl.h) stops when the new support point's *norm*
/// equals the current distance, a test meant for a support point already in the simplex; a
/// mirror-image point of the Minkowski difference at the same norm stops it too. Grid boxes with
/// coincident faces make such points: their tied support vertices (FCL's box support picks by the
/// sign of the direction rotated into the box frame, rounding decides a zero component) cancel.
/// Grid spheres and capsules make them too: GJK's first support points, along libccd's first
/// direction (1, 0, 0), give v; the next, along −v, lands at the same norm (seed 98765 case
/// 35505: spheres 2.48 apart, FCL 3).
bool fclGjkStoppedOnEqualNorm(const DiffCase& c, const J& query, const J& got, double tau) {
  if (!got.contains("point_a") || !got.contains("point_b") || !got.contains("distance")) return false;
  const J a = gjkOperand(c, query["a"], got, "triangle_a"), b = gjkOperand(c, query["b"], got, "triangle_b");
  if (a.is_null() || b.is_null()) return false;
  const Vec3d v = toVec(got["point_a"]) - toVec(got["point_b"]);
  const double d = v.norm();
  if (!(d > tau) || std::fabs(d - got["distance"].get<double>()) > tau) return false;
  const Vec3d u = v / d;
  for (const Vec3d& pa : supportPoints(a, -u, tau))
    for (const Vec3d& pb : supportPoints(b, u, tau)) {
      const Vec3d w = pa - pb;
      if (std::fabs(w.norm() - d) <= tau && w.dot(u) < d - tau) return true;
    }
  return false;
}

/// FCL's `distance` of a mesh operand whose wrong answer comes from *exact's* nearest triangle:
/// FCL measures a BVHModel against a shape triangle by triangle (shapeTriangleDistance, libccd's
/// GJK) and keeps the least; when libccd's equal-norm stop (fclGjkStoppedOnEqualNorm) leaves the
/// triangle that should win at a larger distance, another triangle, measured right, wins instead
/// and FCL names that one, so the rule on FCL's named triangle finds nothing (seed 98765 cases
/// 552898 and 828054: a box mesh whose nearest edge's two ends are as far from the hull's corner,
/// GJK stops on the first end; case 950260: a soup triangle, 6.40 for 2). Shown on the case by
/// asking FCL that triangle alone (`probePeer`, the same transform; the fcl world measures it as a
/// one-triangle BVHModel by the same GJK): its answer is above exact's and not below FCL's mesh
/// answer, and it stopped on an equal-norm support point; and FCL's answer is its own answer on
/// the triangle it names (asked alone the same way), the least it found.
bool fclMeshTriangleStoppedOnEqualNorm(const DiffCase& c, const J& query, const J& got, const J& exact, double tau,
                                       const std::function<Answer(const DiffCase&)>& probePeer) {
  if (!probePeer || !got.contains("distance")) return false;
  // FCL's distance of the triangle `names[key]` of the mesh operand `side` alone; null if unknown
  const auto alone = [&](const char* side, const J& names, const std::string& key, DiffCase* one, J* q) -> Answer {
    const J triangle = gjkOperand(c, query[side], names, key.c_str());
    if (triangle.is_null()) return nullptr;
    *one = c;
    *q = query;
    (*q)[side] = triangle;
    one->query = q->dump();
    Answer a = probePeer(*one);
    return hasError(a) || !a.contains("distance") ? Answer(nullptr) : a;
  };
  for (const char* side : {"a", "b"}) {
    const std::string key = std::string("triangle_") + side;
    if (!query[side].contains("mesh") || !exact.contains(key) || !got.contains(key) || exact[key] == got[key]) continue;
    DiffCase one, named;
    J q, qNamed;
    const Answer atExact = alone(side, exact, key, &one, &q);
    if (atExact.is_null()) continue;
    const double d = atExact["distance"].get<double>();
    if (!(d > narrowNumber(c.op, exact) + tau && d >= narrowNumber(c.op, got) - tau &&
          fclGjkStoppedOnEqualNorm(one, q, atExact, tau)))
      continue;
    const Answer atNamed = alone(side, got, key, &named, &qNamed);
    if (!atNamed.is_null() && std::fabs(atNamed["distance"].get<double>() - narrowNumber(c.op, got)) <= tau) return true;
  }
  return false;
}

/// FCL's `distance` of penetrating convex shapes answered as a touching contact by libccd's EPA
/// on a two-point GJK simplex: GJK's first support points, along libccd's first direction
/// (1, 0, 0) and then along −w0, are w0 and w1 = −λ·w0 (λ > 0, within `tau`), a segment through
/// the origin, so GJK reports an intersection at once (doSimplex2, FCL 0.7 gjk_libccd-inl.h).
/// EPA's simplexToPolytope2 then declares a touching contact as soon as a support point it draws
/// equals w0 or w1 (a vertex of a polytope is the support point of a whole cone of directions,
/// so this happens deep inside too) and answers the segment: depth 0, both points at the
/// origin's place on it. Shown by FCL's reported points: point_a and point_b are A's point of
/// that place, (1 − t)·a0 + t·a1 with t = |w0| / (|w0| + |w1|), within `tau`.
bool fclEpaTouchingOnGjkSegment(const J& query, const J& got, double tau) {
  if (!got.contains("point_a") || !got.contains("point_b") || !got.contains("distance")) return false;
  const J& a = query["a"];
  const J& b = query["b"];
  const Vec3d pa = toVec(got["point_a"]), pb = toVec(got["point_b"]);
  if (std::fabs(got["distance"].get<double>()) > tau || (pa - pb).norm() > tau) return false;
  const Vec3d first(1, 0, 0);
  for (const Vec3d& a0 : supportPoints(a, first, tau))
    for (const Vec3d& b0 : supportPoints(b, -first, tau)) {
      const Vec3d w0 = a0 - b0;
      if (!(w0.norm() > tau)) continue;
      for (const Vec3d& a1 : supportPoints(a, -w0, tau))
        for (const Vec3d& b1 : supportPoints(b, w0, tau)) {
          const Vec3d w1 = a1 - b1;
          const double t = w0.norm() / (w0.norm() + w1.norm());
          if (w0.dot(w1) < 0 && w0.cross(w1).norm() <= tau * (w0.norm() + w1.norm()) &&
              ((1 - t) * a0 + t * a1 - pa).norm() <= tau)
            return true;
        }
    }
  return false;
}

/// The deepest contact of a `contacts` answer; null when it has none.
const J* deepestContact(const J& answer) {
  const J* deepest = nullptr;
  for (const auto& k : answer["contacts"])
    if (!deepest || k["depth"].get<double>() > (*deepest)["depth"].get<double>()) deepest = &k;
  return deepest;
}

/// The points p − q over p in a, q in b: the vertices (and inner points) of the Minkowski
/// difference of two polytopes, or of two cores.
std::vector<Vec3d> differences(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  std::vector<Vec3d> w;
  for (const Vec3d& p : a)
    for (const Vec3d& q : b) w.push_back(p - q);
  return w;
}

/// The point of segment ab nearest the origin (double).
Vec3d segmentPointNearestOrigin(const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp(-a.dot(ab) / len2, 0.0, 1.0) : 0.0;
  return a + t * ab;
}

/// The point of triangle abc nearest the origin (double): the origin's projection on its plane
/// when inside, else the nearest of its edges' points.
Vec3d trianglePointNearestOrigin(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d n = (b - a).cross(c - a);
  if (n.squaredNorm() > 0) {
    const Vec3d q = n * (a.dot(n) / n.squaredNorm());  // the origin projected on the plane
    if ((b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 && (a - c).cross(q - c).dot(n) >= 0) return q;
  }
  Vec3d best = segmentPointNearestOrigin(a, b);
  for (const Vec3d& e : {segmentPointNearestOrigin(b, c), segmentPointNearestOrigin(c, a)})
    if (e.norm() < best.norm()) best = e;
  return best;
}

/// Whether v is, within `tau`, the point nearest the origin of one, two or three of the points
/// `w` (a GJK simplex over them).
bool nearestOnASimplex(const std::vector<Vec3d>& w, const Vec3d& v, double tau) {
  for (std::size_t i = 0; i < w.size(); ++i) {
    if ((w[i] - v).norm() <= tau) return true;
    for (std::size_t j = i + 1; j < w.size(); ++j) {
      if ((segmentPointNearestOrigin(w[i], w[j]) - v).norm() <= tau) return true;
      for (std::size_t k = j + 1; k < w.size(); ++k)
        if ((trianglePointNearestOrigin(w[i], w[j], w[k]) - v).norm() <= tau) return true;
    }
  }
  return false;
}

/// Bullet's `contacts` of two convex operands stopped by btGjkPairDetector before converging.
/// Bullet runs GJK on the cores (a sphere's centre, a capsule's segment; polytopes as they are)
/// and reports distance |v| − r, r the radii, along v̂, v the closest point of its simplex to the
/// origin; EPA runs only when the cores cross or |v| < gGjkEpaPenetrationTolerance (1e-3). GJK
/// stops without its convergence test when btVoronoiSimplexSolver::closest rejects the new
/// simplex (m_degenerateSimplex 3): the closest point's barycentric coordinates must all be ≥ 0,
/// and in the face-region formula 1 − v − w rounds to −1 float ulp when the closest point lies on
/// an edge (seed 98765 cases 9175 and 503147, checked on Bullet itself); GJK then reports the
/// previous simplex's v. Shown on the case: Bullet's answer is v = ±(r − depth)·n̂ for the
/// deepest contact (or, when Bullet reports none, for the deepest of its answer to the case with
/// `margin` 4s, `probePeer`, which lets the GJK distance through), v is the point nearest the
/// origin of 1–3 points of the cores' Minkowski difference (a GJK simplex, within `tau`), |v| ≥
/// 1e-3 (no EPA), and |v| exceeds the cores' true distance, r − exact's deepest depth (itself
/// beyond `tau`: cores that cross go to EPA), by more than `tau`: a converged GJK (REL_ERROR2 =
/// 1e-6 on |v|²) cannot report that.
bool bulletGjkStoppedEarly(const DiffCase& c, const J& query, const J& got, const J& exact, double s, double tau,
                           const std::function<Answer(const DiffCase&)>& probePeer, bool crossingPolytopes = false) {
  if (!c.setup.empty() || !query.contains("a") || !query.contains("b") || !narrowVerdict(c.op, exact)) return false;
  double ra = 0, rb = 0;
  const std::vector<Vec3d> pa = corePoints(query["a"], &ra), pb = corePoints(query["b"], &rb);
  if (pa.empty() || pb.empty()) return false;
  J answer = got;
  if (!narrowVerdict(c.op, got)) {
    if (!probePeer) return false;
    DiffCase wider = c;
    J q = query;
    q["margin"] = 4 * s;
    wider.query = q.dump();
    answer = probePeer(wider);
    if (hasError(answer) || !narrowVerdict(c.op, answer)) return false;
  }
  const J* deepest = deepestContact(answer);
  const Vec3d n = toVec((*deepest)["normal"]);
  const double r = ra + rb, length = r - (*deepest)["depth"].get<double>();
  // crossingPolytopes: radius-0 cores exact finds crossing (true distance 0); a converged GJK
  // would have gone on to EPA
  const bool crossing = crossingPolytopes && r == 0 && narrowNumber(c.op, exact) > tau;
  const double trueLength = crossing ? 0.0 : r - narrowNumber(c.op, exact);
  if (!(n.norm() > 0) || !(crossing || trueLength > tau) || !(length >= 1e-3) || !(length > trueLength + tau))
    return false;
  const std::vector<Vec3d> w = differences(pa, pb);
  for (const double sign : {1.0, -1.0})
    if (nearestOnASimplex(w, sign * length * n.normalized(), tau)) return true;
  return false;
}

/// Whether four of the points `w` (a Minkowski difference's vertices) span a tetrahedron that
/// holds the origin (strictly on the inner side of every face) while its triple product
/// |(d − a)·((b − a)×(c − a))| is below 1e-4: btVoronoiSimplexSolver::pointOutsideOfPlane (float
/// Bullet, CATCH_DEGENERATE_TETRAHEDRON) calls such a GJK simplex degenerate (signd² < 1e-4²), an
/// absolute test on a volume, so closest() fails instead of reporting the origin inside.
bool flatTetrahedronAroundOrigin(const std::vector<Vec3d>& w) {
  const std::size_t n = w.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      for (std::size_t k = j + 1; k < n; ++k)
        for (std::size_t l = k + 1; l < n; ++l) {
          const Vec3d v[4] = {w[i], w[j], w[k], w[l]};
          const double volume = (v[3] - v[0]).dot((v[1] - v[0]).cross(v[2] - v[0]));
          if (!(std::fabs(volume) < 1e-4) || volume == 0) continue;
          bool inside = true;
          for (int f = 0; f < 4 && inside; ++f) {  // face without vertex f: origin on f's side
            const Vec3d& a = v[(f + 1) % 4];
            const Vec3d& b = v[(f + 2) % 4];
            const Vec3d& c = v[(f + 3) % 4];
            const Vec3d normal = (b - a).cross(c - a);
            inside = (-a).dot(normal) * (v[f] - a).dot(normal) > 0;
          }
          if (inside) return true;
        }
  return false;
}

/// Bullet's miss of a `mesh_triangle` (no transform) that exact hits: btBvhTriangleMeshShape
/// against a btTriangleShape runs btConvexConcaveCollisionAlgorithm, i.e. btGjkPairDetector on
/// the query triangle and each mesh triangle its box overlaps. The mesh triangles the query
/// touches (those whose box overlaps the query's and which exact's `triangle_triangle` finds
/// touching the query, at most 8) each cross it (exact's `contacts` depth beyond `tau`), and
/// Bullet asked the pair as `contacts` reports it apart on a GJK stopped early
/// (bulletGjkStoppedEarly with crossing polytopes: its gap, with `margin` 4s, is ≥ 1e-3 and the
/// point nearest the origin of 1–3 points of A − B), and A − B has a tetrahedron around the origin
/// that Bullet's simplex solver calls degenerate (flatTetrahedronAroundOrigin). Seed 98765 case
/// 711448: a query triangle crossing bunny00's triangle 57672 (about 0.01 across) 0.0033 deep,
/// Bullet 0.0036 apart; btGjkPairDetector on the pair (query first) reaches a 4-point simplex
/// around the origin whose triple product is 3.2e-5 (below 1e-4), closest() fails
/// (m_degenerateSimplex 3) and GJK reports its previous v (m_lastUsedMethod 1); scaled by 2 (exact
/// in float) the product is 8 times larger and EPA finds the crossing.
bool bulletMeshTrianglesApartOnAnEarlyGjkStop(const DiffCase& c, const J& query, const J& exact, double s, double tau,
                                              const std::function<Answer(const DiffCase&)>& probeExact,
                                              const std::function<Answer(const DiffCase&)>& probePeer) {
  if (!probePeer || !probeExact || c.op != "mesh_triangle" || query.contains("transform") ||
      !query.contains("triangle") || !query["mesh"].is_string() || !exact.value("hit", false))
    return false;
  std::vector<std::array<Vec3d, 3>> inline_;
  const Mesh* mesh = caseMesh(c, query["mesh"].get<std::string>(), inline_);
  std::vector<std::array<Vec3d, 3>> tris = inline_;
  if (mesh) {
    tris.clear();
    for (std::uint32_t i = 0; i < mesh->triangleCount(); ++i) {
      const Triangle m = mesh->triangle(i);
      tris.push_back({m.a.cast<double>(), m.b.cast<double>(), m.c.cast<double>()});
    }
  }
  Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : query["triangle"]) lo = lo.cwiseMin(toVec(p)), hi = hi.cwiseMax(toVec(p));
  int crossing = 0;
  for (const auto& t : tris) {
    Vec3d tlo = t[0].cwiseMin(t[1]).cwiseMin(t[2]), thi = t[0].cwiseMax(t[1]).cwiseMax(t[2]);
    if ((tlo.array() > hi.array() + tau).any() || (thi.array() < lo.array() - tau).any()) continue;
    J triangle = J::array();
    for (const Vec3d& v : t) triangle.push_back({v.x(), v.y(), v.z()});
    DiffCase pair = c;
    pair.setup.clear();
    pair.sharedSetup = false;
    pair.op = "triangle_triangle";
    pair.query = J{{"op", "triangle_triangle"}, {"a", triangle}, {"b", query["triangle"]}}.dump();
    const Answer touches = probeExact(pair);
    if (hasError(touches) || !touches.value("hit", false)) continue;
    if (++crossing > 8) return false;
    pair.op = "contacts";
    // the query first, as btConvexConcaveCollisionAlgorithm puts the convex against each triangle
    const J q{{"op", "contacts"}, {"a", {{"triangle", query["triangle"]}}}, {"b", {{"triangle", triangle}}}};
    pair.query = q.dump();
    const Answer exactPair = probeExact(pair), gotPair = probePeer(pair);
    if (hasError(exactPair) || hasError(gotPair) || !narrowVerdict("contacts", exactPair) ||
        !bulletGjkStoppedEarly(pair, q, gotPair, exactPair, s, tau, probePeer, true))
      return false;
    double ra = 0, rb = 0;
    if (!flatTetrahedronAroundOrigin(differences(corePoints(q["a"], &ra), corePoints(q["b"], &rb)))) return false;
  }
  return crossing > 0;
}

/// Bullet's miss of a `triangle_triangle` crossing: btGjkPairDetector hands the crossing pair to
/// btGjkEpaPenetrationDepthSolver, whose first guess is (1, 0, 0) (both triangles sit at the
/// identity: b's origin minus a's is zero); btGjkEpa2's GJK from there stops on a support point
/// within GJK_DUPLICATED_EPS of one of the last four it saw, though it had dropped that point
/// from its simplex and the point lies beyond the origin, and returns the old simplex as
/// separated; `Distance` (the same GJK) gives the gap and btGjkPairDetector reports it (seed
/// 98765 case 191086: 0.0709 apart for 0.08 deep; checked on Bullet's own btGjkEpa2.cpp).
/// Shown on the case, by asking Bullet the same triangles as a `contacts` pair with `margin` 4s
/// (`probePeer`; contactPairTest runs the same convex–convex algorithm): its gap d along n̂ is
/// v = ±d·n̂, the point nearest the origin of 1–3 points of A − B (a GJK simplex, within `tau`),
/// and A − B has a point w with v̂·w < d − `tau`: a support point GJK stopped short of (it had not
/// converged), while exact finds the triangles crossing.
bool bulletTrianglesApartOnAnUnfinishedGjk(const DiffCase& c, const J& query, double s, double tau,
                                          const std::function<Answer(const DiffCase&)>& probePeer) {
  if (!probePeer || !c.setup.empty() || c.op != "triangle_triangle" || !query.contains("a") || !query.contains("b"))
    return false;
  const J a{{"triangle", query["a"]}}, b{{"triangle", query["b"]}};
  DiffCase pair = c;
  pair.op = "contacts";
  pair.query = J{{"op", "contacts"}, {"a", a}, {"b", b}, {"margin", 4 * s}}.dump();
  const Answer answer = probePeer(pair);
  if (hasError(answer) || !narrowVerdict("contacts", answer)) return false;
  const J* deepest = deepestContact(answer);
  const double gap = -(*deepest)["depth"].get<double>();
  const Vec3d n = toVec((*deepest)["normal"]);
  if (!(gap > tau) || !(n.norm() > 0)) return false;
  double ra = 0, rb = 0;
  const std::vector<Vec3d> w = differences(corePoints(a, &ra), corePoints(b, &rb));
  for (const double sign : {1.0, -1.0}) {
    const Vec3d u = sign * n.normalized(), v = gap * u;
    double lowest = std::numeric_limits<double>::infinity();
    for (const Vec3d& x : w) lowest = std::min(lowest, u.dot(x));
    if (lowest < gap - tau && nearestOnASimplex(w, v, tau)) return true;
  }
  return false;
}

/// Bullet's `contacts` of two polytopes (boxes, hulls, triangles: radius 0) answered from an inner
/// face of its EPA polytope. btGjkEpa2's EPA (which btGjkPairDetector calls for crossing shapes)
/// grows a polytope of support points of A − B and reports its face nearest the origin; when a
/// step fails (`expand` finds no horizon: InvalidHull; or out of vertices) it stops and reports
/// the best face so far, inside A − B (seed 98765 case 176110: InvalidHull at iteration 5, a
/// face 0.742 from the origin for a depth of 1; with another initial direction EPA reaches 1).
/// Shown on the case: the plane of Bullet's deepest contact, ±n̂·x = depth, passes through three
/// non-collinear vertices of A − B (within `tau`), and A − B reaches beyond it along its normal
/// by more than `tau` (it is not a supporting plane, as a converged EPA's face is).
bool bulletEpaInnerFace(const J& query, const J& got, double tau) {
  double ra = 0, rb = 0;
  const std::vector<Vec3d> pa = corePoints(query["a"], &ra), pb = corePoints(query["b"], &rb);
  if (pa.empty() || pb.empty() || ra != 0 || rb != 0 || !got.contains("contacts") || got["contacts"].empty()) return false;
  const J* deepest = deepestContact(got);
  const double depth = (*deepest)["depth"].get<double>();
  const Vec3d n = toVec((*deepest)["normal"]);
  if (!(depth > tau) || !(n.norm() > 0)) return false;
  const std::vector<Vec3d> w = differences(pa, pb);
  for (const double sign : {1.0, -1.0}) {
    const Vec3d m = sign * n.normalized();
    std::vector<Vec3d> on;
    double reach = -std::numeric_limits<double>::infinity();
    for (const Vec3d& x : w) {
      reach = std::max(reach, m.dot(x));
      if (std::fabs(m.dot(x) - depth) <= tau) on.push_back(x);
    }
    if (!(reach > depth + tau)) continue;
    for (std::size_t i = 0; i < on.size(); ++i)
      for (std::size_t j = i + 1; j < on.size(); ++j)
        for (std::size_t k = j + 1; k < on.size(); ++k)
          if ((on[j] - on[i]).cross(on[k] - on[i]).norm() > tau * std::max(1.0, (on[j] - on[i]).norm())) return true;
  }
  return false;
}

/// Two box operands whose Minkowski difference is mirror-symmetric about a plane through the
/// origin: a face axis u of one is a face axis of the other (world frames, |u·v| within 1e-9 of
/// 1) and their centres project to the same point on it (within `tau`). Reflection in the plane
/// u·x = 0 maps a − b onto itself, so support points come in mirror pairs and a GJK simplex
/// can hold the origin on a face: Bullet's EPA (btGjkEpaSolver2::Penetration, which
/// contactPairTest's convex-convex algorithm calls; Bullet has no box-box case for closest
/// points) then ends on a face of its polytope inside the difference, and Penetration reports
/// that face's distance as the depth (seed 777 case 13091, seed 9001 cases 3431 and 10095: 0 or
/// 0.89 for 1 or 2; the same boxes with centres 0.1 apart along u get the right depth).
bool boxesMirrorSymmetric(const J& query, double tau) {
  if (!query.contains("a") || !query.contains("b") || !query["a"].contains("box") || !query["b"].contains("box"))
    return false;
  struct Frame {
    Vec3d centre;
    Eigen::Matrix3d axes;  // columns
  };
  const auto frame = [](const J& operand) {
    const Placement place(operand.contains("transform") ? &operand["transform"] : nullptr);
    const J& box = operand["box"];
    Frame f;
    f.centre = place.r * toVec(box["center"]) + place.t;
    for (int i = 0; i < 3; ++i) f.axes.col(i) = place.r * toVec(box["axes"][std::size_t(i)]).normalized();
    return f;
  };
  const Frame fa = frame(query["a"]), fb = frame(query["b"]);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (std::fabs(std::fabs(fa.axes.col(i).dot(fb.axes.col(j))) - 1) <= 1e-9 &&
          std::fabs((fa.centre - fb.centre).dot(fa.axes.col(i))) <= tau)
        return true;
  return false;
}

/// The triangles of a mesh_* / model_* query's mesh, placed in the world (the model's world
/// transform, or the query's `transform`); empty when the mesh is unknown.
std::vector<std::array<Vec3d, 3>> placedQueryTriangles(const DiffCase& c, const J& query) {
  J operand;
  if (startsWith(c.op, "model_")) {
    if (query.contains("model") && query["model"].is_string()) operand = modelOperand(c, query["model"].get<std::string>());
  } else if (query.contains("mesh") && query["mesh"].is_string()) {
    operand = J{{"mesh", query["mesh"]}};
    if (query.contains("transform")) operand["transform"] = query["transform"];
  }
  std::vector<std::array<Vec3d, 3>> tris;
  if (operand.is_null() || !operand["mesh"].is_string()) return tris;
  const Placement place(operand.contains("transform") ? &operand["transform"] : nullptr);
  if (const Mesh* mesh = caseMesh(c, operand["mesh"].get<std::string>(), tris)) {
    for (std::uint32_t i = 0; i < mesh->triangleCount(); ++i) {
      const Triangle t = mesh->triangle(i);
      tris.push_back({t.a.cast<double>(), t.b.cast<double>(), t.c.cast<double>()});
    }
  }
  for (auto& t : tris)
    for (Vec3d& v : t) v = place.r * v + place.t;
  return tris;
}

/// mesh_plane / model_plane, mesh_triangle / model_triangle: the mesh (placed in the world)
/// reaches the query's plane or triangle, and every contact only touches: no triangle has
/// corners more than `tau` on both sides of the plane; for a triangle, exact's signed distance
/// (`probeExact`) of every mesh triangle within `tau` of it is at least −tau. A model on both
/// sides of a plane through two triangles that each touch it stays a hit under any small move,
/// though no single triangle crosses.
bool meshOnlyTouches(const DiffCase& c, const J& query, double tau,
                     const std::function<Answer(const DiffCase&)>& probeExact) {
  const bool plane = c.op == "mesh_plane" || c.op == "model_plane";
  const bool triangle = c.op == "mesh_triangle" || c.op == "model_triangle";
  if (!(plane && query.contains("plane")) && !(triangle && query.contains("triangle"))) return false;
  const auto tris = placedQueryTriangles(c, query);
  if (tris.empty()) return false;
  bool touches = false;
  if (plane) {
    const Vec3d n = toVec(query["plane"]["normal"]);
    const double d = query["plane"]["d"].get<double>(), len = n.norm();
    if (!(len > 0)) return false;
    for (const auto& t : tris) {
      double lo = INFINITY, hi = -INFINITY;
      for (const Vec3d& v : t) {
        const double side = (n.dot(v) - d) / len;
        lo = std::min(lo, side), hi = std::max(hi, side);
      }
      if (lo < -tau && hi > tau) return false;
      if (lo <= tau && hi >= -tau) touches = true;
    }
    return touches;
  }
  const std::array<Vec3d, 3> q = {toVec(query["triangle"][0]), toVec(query["triangle"][1]), toVec(query["triangle"][2])};
  const Triangle qr{q[0].cast<Real>(), q[1].cast<Real>(), q[2].cast<Real>()};
  for (const auto& t : tris) {
    const Triangle tr{t[0].cast<Real>(), t[1].cast<Real>(), t[2].cast<Real>()};
    if (!(double(closestPoints(qr, tr).distance) <= tau)) continue;
    J pair = J{{"op", "distance"}, {"a", {{"triangle", J::array()}}}, {"b", {{"triangle", query["triangle"]}}}};
    for (const Vec3d& v : t) pair["a"]["triangle"].push_back({v.x(), v.y(), v.z()});
    DiffCase d;
    d.op = "distance";
    d.query = pair.dump();
    const Answer a = probeExact(d);
    if (hasError(a) || !a.contains("distance") || !(a["distance"].get<double>() >= -tau)) return false;
    touches = true;
  }
  return touches;
}

/// A mesh_distance or model_distance answer of exact whose witness triangle (triangle_a or
/// triangle_b) is degenerate (collinear or repeated corners).
bool exactWitnessOnDegenerateTriangle(const DiffCase& c, const J& query, const J& exact) {
  if (!isMeshPairDistance(c.op) || !exact.value("found", false)) return false;
  for (const char* side : {"a", "b"}) {
    const std::string key = std::string("triangle_") + side;
    if (!query.contains(side) || !query[side].is_string() || !exact.contains(key) || !exact[key].is_number_unsigned())
      continue;
    std::string name = query[side].get<std::string>();
    if (c.op == "model_distance") {
      const J operand = modelOperand(c, name);
      if (operand.is_null() || !operand["mesh"].is_string()) continue;
      name = operand["mesh"].get<std::string>();
    }
    const auto t = caseMeshTriangle(c, name, exact[key].get<std::size_t>());
    if (t && degenerate(*t)) return true;
  }
  return false;
}

/// `distance` with a mesh operand: the triangle the peer names as its nearest (`triangle_a` /
/// `triangle_b`) is collinear or has repeated corners. FCL measures a mesh against a shape
/// triangle by triangle; on a degenerate one its sphere–triangle distance (whose normal it
/// normalises) and GJK answer 0 with uninitialised points, and that 0 is the least (seed 98765
/// case 193812: a sphere 0.97 from a mesh whose triangle 0 repeats a corner; the mesh without it
/// gets 0.97).
bool peerWitnessOnDegenerateTriangle(const DiffCase& c, const J& query, const J& got) {
  if (c.op != "distance") return false;
  for (const char* side : {"a", "b"}) {
    const std::string key = std::string("triangle_") + side;
    if (!query.contains(side) || !query[side].is_object() || !query[side].contains("mesh") ||
        !query[side]["mesh"].is_string() || !got.contains(key) || !got[key].is_number_integer() || got[key].get<long long>() < 0)
      continue;
    const auto t = caseMeshTriangle(c, query[side]["mesh"].get<std::string>(), got[key].get<std::size_t>());
    if (t && degenerate(*t)) return true;
  }
  return false;
}

/// `contacts` with a mesh operand: exact's deepest contact lies on a mesh triangle
/// (`feature_a` / `feature_b`) that is collinear or has repeated corners. Bullet's per-triangle
/// tests see no normal there (SphereTriangleDetector skips |n|² < FLT_EPSILON²) and report no
/// contact with it (seed 98765 case 419716: a sphere 0.59 deep on a mesh triangle that repeats
/// a corner).
bool exactContactOnDegenerateTriangle(const DiffCase& c, const J& query, const J& exact) {
  if (c.op != "contacts" || !exact.contains("contacts") || !exact["contacts"].is_array() || exact["contacts"].empty())
    return false;
  const J* deepest = nullptr;
  for (const J& k : exact["contacts"])
    if (!deepest || k.value("depth", 0.0) > deepest->value("depth", 0.0)) deepest = &k;
  for (const char* side : {"a", "b"}) {
    const std::string key = std::string("feature_") + side;
    if (!query.contains(side) || !query[side].is_object() || !query[side].contains("mesh") ||
        !query[side]["mesh"].is_string() || !deepest->contains(key) || !(*deepest)[key].is_number_integer() ||
        (*deepest)[key].get<long long>() < 0)
      continue;
    const auto t = caseMeshTriangle(c, query[side]["mesh"].get<std::string>(), (*deepest)[key].get<std::size_t>());
    if (t && degenerate(*t)) return true;
  }
  return false;
}

/// A zero-radius sphere, a flat box, a capsule with a = b, a hull of fewer than 4 points or a
/// degenerate triangle among the operands of a narrow-phase query.
bool degenerateOperand(const J& query) {
  for (const char* side : {"a", "b"}) {
    if (!query.contains(side) || !query[side].is_object()) continue;
    const J& o = query[side];
    if (o.contains("sphere") && o["sphere"]["radius"].get<double>() == 0) return true;
    if (o.contains("box"))
      for (const auto& h : o["box"]["half"])
        if (h.get<double>() == 0) return true;
    if (o.contains("capsule") && o["capsule"]["a"] == o["capsule"]["b"]) return true;
    if (o.contains("hull") && o["hull"]["points"].size() < 4) return true;
    if (o.contains("triangle") && degenerate({readV(o["triangle"][0]), readV(o["triangle"][1]), readV(o["triangle"][2])}))
      return true;
  }
  return false;
}

// ---- JSON editing helpers ------------------------------------------------------------------------

void moveVec(J& v, const Vec3d& off) {
  for (std::size_t i = 0; i < 3; ++i) v[i] = v[i].get<double>() + off[Eigen::Index(i)];
}

/// Moves a protocol transform object (created when absent, identity) by off.
void moveTransform(J& transform, const Vec3d& off) {
  if (!transform.is_object()) transform = J::object();
  if (!transform.contains("translation")) transform["translation"] = J::array({0, 0, 0});
  moveVec(transform["translation"], off);
}

/// Moves a shape field of a query object; returns false when there is none.
bool moveShape(J& q, const Vec3d& off) {
  bool moved = false;
  if (q.contains("point") && q["point"].is_array()) moveVec(q["point"], off), moved = true;
  if (q.contains("sphere")) moveVec(q["sphere"]["center"], off), moved = true;
  if (q.contains("aabb")) moveVec(q["aabb"]["min"], off), moveVec(q["aabb"]["max"], off), moved = true;
  if (q.contains("obb")) moveVec(q["obb"]["center"], off), moved = true;
  if (q.contains("plane")) {
    const V n = readV(q["plane"]["normal"]);
    q["plane"]["d"] = q["plane"]["d"].get<double>() + n[0] * off[0] + n[1] * off[1] + n[2] * off[2];
    moved = true;
  }
  if (q.contains("ray")) moveVec(q["ray"]["origin"], off), moved = true;
  if (q.contains("segment")) moveVec(q["segment"]["start"], off), moveVec(q["segment"]["end"], off), moved = true;
  return moved;
}

}  // namespace

bool answersAgree(const std::string& queryLine, const Answer& got, const Answer& exact, double tolerance) {
  if (hasError(got) || hasError(exact)) return false;
  const J query = J::parse(queryLine, nullptr, false);
  if (!query.is_object() || !query.contains("op") || !query["op"].is_string()) return false;
  return compareAnswers(query["op"].get<std::string>(), query, got, exact, tolerance) == Difference::None;
}

std::string_view verdictName(Verdict verdict) {
  switch (verdict) {
    case Verdict::Agree: return "agree";
    case Verdict::WithinTolerance: return "within_tolerance";
    case Verdict::PeerWrong: return "peer_wrong";
    case Verdict::CruxWrong: return "crux_wrong";
    case Verdict::Unsupported: return "unsupported";
    case Verdict::Error: return "error";
    case Verdict::NoArbiter: return "no_arbiter";
    case Verdict::PeerFailed: return "peer_failed";
  }
  return "?";
}

double caseMagnitude(const DiffCase& c) {
  double s = c.extraMagnitude;
  std::function<void(const J&, const std::string&)> scan = [&](const J& j, const std::string& key) {
    if (key == "dir" || key == "normal" || key == "axes" || key == "rotation" || key == "triangles" || key == "max")
      return;
    if (j.is_object()) {
      for (auto it = j.begin(); it != j.end(); ++it) scan(*it, it.key());
    } else if (j.is_array()) {
      for (const auto& e : j) scan(e, key);
    } else if (j.is_number()) {
      s = std::max(s, std::fabs(j.get<double>()));
    }
  };
  for (const auto& line : c.setup) scan(J::parse(line, nullptr, false), "");
  scan(J::parse(c.query, nullptr, false), "");
  return s;
}

std::optional<DiffCase> translatedCase(const DiffCase& c, const Vec3d& offset, std::string_view model) {
  DiffCase out = c;
  J q = J::parse(c.query, nullptr, false);
  if (!q.is_object()) return std::nullopt;
  if (c.op == "distance" || c.op == "contacts" || c.op == "cast") {
    if (!q.contains("b") || !q["b"].is_object()) return std::nullopt;
    J& tb = q["b"]["transform"];
    moveTransform(tb, offset);
  } else if (c.op == "mesh_mesh" || c.op == "mesh_distance") {
    J& tb = q["transform_b"];
    moveTransform(tb, offset);
  } else if (c.op == "model_distance") {
    // move model b (model a when b is an ancestor of a, which would carry a along): its local
    // translation in the last line that sets it, i.e. by R_parent·offset in the world
    if (!q.contains("a") || !q["a"].is_string() || !q.contains("b") || !q["b"].is_string()) return std::nullopt;
    const std::string a = q["a"].get<std::string>();
    std::string who = q["b"].get<std::string>();
    std::map<std::string, std::string> parent;
    for (const auto& line : out.setup) {
      const J m = J::parse(line, nullptr, false);
      if (!m.is_object()) continue;
      const std::string op = m.value("op", "");
      const J* child = op == "add_model" ? &m["name"] : op == "set_parent" ? &m["model"] : nullptr;
      if (child && child->is_string())
        parent[child->get<std::string>()] = m.contains("parent") && m["parent"].is_string() ? m["parent"].get<std::string>() : "";
    }
    std::string up = a;
    for (std::size_t hops = 0; hops <= parent.size() && parent.count(up); ++hops) {
      up = parent[up];
      if (up == who) {
        who = a;
        break;
      }
    }
    for (auto line = out.setup.rbegin(); line != out.setup.rend(); ++line) {
      J m = J::parse(*line, nullptr, false);
      if (!m.is_object()) continue;
      const std::string op = m.value("op", "");
      const bool sets = (op == "add_model" && m.value("name", "") == who) ||
                        (op == "set_transform" && m.value("model", "") == who);
      if (!sets) continue;
      moveTransform(m["transform"], offset);
      *line = m.dump();
      return out;
    }
    return std::nullopt;
  } else if (c.op == "scene_pairs") {
    // move `model` (its local translation in the last line that sets it), or the last model added
    for (auto line = out.setup.rbegin(); line != out.setup.rend(); ++line) {
      J m = J::parse(*line, nullptr, false);
      if (!m.is_object()) continue;
      const std::string op = m.value("op", "");
      const bool sets = model.empty() ? op == "add_model"
                                      : (op == "add_model" && m.value("name", "") == model) ||
                                            (op == "set_transform" && m.value("model", "") == model);
      if (!sets) continue;
      moveTransform(m["transform"], offset);
      *line = m.dump();
      return out;
    }
    return std::nullopt;
  } else {
    bool moved = moveShape(q, offset);
    if (c.op == "triangle_triangle" && q.contains("b")) {
      for (auto& p : q["b"]) moveVec(p, offset);
      moved = true;
    } else if ((startsWith(c.op, "mesh_") || startsWith(c.op, "model_")) && q.contains("triangle")) {
      for (auto& p : q["triangle"]) moveVec(p, offset);
      moved = true;
    }
    if (!moved) return std::nullopt;
  }
  out.query = q.dump();
  return out;
}

// ---- running -------------------------------------------------------------------------------------

/// Time limit of a case's setup lines in a worker (loading a real mesh into FCL takes seconds
/// on a loaded machine); the queries have DiffOptions::peerTimeoutSeconds.
constexpr double kSetupTimeoutSeconds = 60;

struct DiffRunner::Impl {
  struct Prepared {
    std::unique_ptr<BatchState> state;
    std::optional<Answer> setupError;
  };
  /// A shared setup prepared in a worker's slot.
  struct Slot {
    int slot = 0;
    std::optional<Answer> setupError;
  };
  std::map<std::string, Prepared> shared;
  std::map<std::string, Slot> sharedSlots;  ///< by backend + setup
  std::map<std::string, WorldTolerance, std::less<>> tolerances;
  std::string workerExecutable;
  double timeoutSeconds = 2;
  std::map<Backend, std::unique_ptr<PeerWorker>> workers;

  /// The worker answering `backend`; null when it answers in process.
  PeerWorker* worker(Backend backend) {
    if (workerExecutable.empty() || (backend != Backend::Fcl && backend != Backend::Bullet)) return nullptr;
    auto& w = workers[backend];
    if (!w)
      w = std::make_unique<PeerWorker>(
          PeerWorkerOptions{workerExecutable, backend, timeoutSeconds, std::max(kSetupTimeoutSeconds, timeoutSeconds)});
    return w.get();
  }
};

DiffRunner::DiffRunner(std::string workerExecutable, double timeoutSeconds) : impl_(std::make_unique<Impl>()) {
  impl_->workerExecutable = std::move(workerExecutable);
  impl_->timeoutSeconds = timeoutSeconds;
}
DiffRunner::~DiffRunner() = default;

namespace {

/// Runs setup lines; returns the first error answer, if any.
std::optional<Answer> runSetup(const std::vector<std::string>& setup, BatchState& state) {
  for (const auto& line : setup) {
    Answer a = answerLine(line, state);
    if (hasError(a)) {
      a["error"] = "setup: " + a["error"].get<std::string>();
      return a;
    }
  }
  return std::nullopt;
}

/// The first error among a worker's answers to setup lines, as runSetup reports it.
std::optional<Answer> setupError(const std::vector<std::string>& answers, std::size_t setupLines) {
  for (std::size_t i = 0; i < setupLines && i < answers.size(); ++i) {
    Answer a = Answer::parse(answers[i], nullptr, false);
    if (!a.is_object()) a = Answer{{"error", "unreadable answer: " + answers[i]}};
    if (hasError(a)) {
      a["error"] = "setup: " + a["error"].get<std::string>();
      return a;
    }
  }
  return std::nullopt;
}

Answer parsedAnswer(const std::string& text) {
  Answer a = Answer::parse(text, nullptr, false);
  return a.is_object() ? a : Answer{{"error", "unreadable answer: " + text}};
}

}  // namespace

Answer DiffRunner::run(const DiffCase& c, std::string_view backend) {
  const auto b = parseBackend(backend);
  if (!b) throw InvalidInput("backends: unknown backend \"" + std::string(backend) + "\"");
  if (PeerWorker* worker = impl_->worker(*b)) {
    std::vector<std::string> lines = c.setup;
    lines.push_back(c.query);
    if (!c.sharedSetup) {
      const std::vector<std::string> answers = worker->answer(lines, 0, true, c.setup.size());
      if (auto error = setupError(answers, c.setup.size())) return *error;
      return parsedAnswer(answers.back());
    }
    std::string key(backend);
    for (const auto& line : c.setup) key += "\n" + line;
    auto it = impl_->sharedSlots.find(key);
    if (it == impl_->sharedSlots.end()) {
      Impl::Slot slot;
      slot.slot = int(impl_->sharedSlots.size()) + 1;
      const std::vector<std::string> answers = worker->answer(lines, slot.slot, true, c.setup.size());
      slot.setupError = setupError(answers, c.setup.size());
      impl_->sharedSlots.emplace(key, slot);
      return slot.setupError ? *slot.setupError : parsedAnswer(answers.back());
    }
    if (it->second.setupError) return *it->second.setupError;
    return parsedAnswer(worker->answer({c.query}, it->second.slot).front());
  }
  BatchOptions options;
  options.backend = *b;
  if (c.sharedSetup) {
    std::string key(backend);
    for (const auto& line : c.setup) key += "\n" + line;
    auto it = impl_->shared.find(key);
    if (it == impl_->shared.end()) {
      Impl::Prepared p;
      p.state = std::make_unique<BatchState>(options);
      p.setupError = runSetup(c.setup, *p.state);
      it = impl_->shared.emplace(key, std::move(p)).first;
    }
    if (it->second.setupError) return *it->second.setupError;
    return answerLine(c.query, *it->second.state);
  }
  BatchState state(options);
  if (auto error = runSetup(c.setup, state)) return *error;
  return answerLine(c.query, state);
}

WorldTolerance DiffRunner::tolerance(std::string_view backend) {
  auto it = impl_->tolerances.find(backend);
  if (it != impl_->tolerances.end()) return it->second;
#ifdef CRUX_DIFF_HAVE_ORACLE
  const WorldTolerance tol = makeWorld(backend)->tolerance();
#else
  throw InvalidInput("backends: crux was built without the oracle backends (CRUX_BUILD_ORACLE)");
#endif
  impl_->tolerances.emplace(std::string(backend), tol);
  return tol;
}

// ---- classification ------------------------------------------------------------------------------

/// Whether a triangle of the case is a sliver thinner than τ (the peer's tolerance): within τ of
/// the segment it nearly is.
bool thinnerThan(const std::vector<std::array<V, 3>>& tris, double tau) {
  for (const auto& t : tris)
    if (smallestHeight(t) <= tau) return true;
  return false;
}

/// Whether exact's hit is a contact the shapes only graze: b moved by up to 1e-3 × s (the
/// lattice of probeOffsets) makes exact miss. The peers' absolute tolerances lose or delay such
/// contacts (libccd's 1e-6, Bullet's float GJK).
bool onlyGrazes(const DiffCase& c, const J& exact, double s, const std::function<Answer(const DiffCase&)>& probeExact) {
  if (!exact.value("hit", false)) return false;
  for (const Vec3d& off : probeOffsets(1e-3 * s, false)) {
    const auto moved = translatedCase(c, off, "");
    if (!moved) return false;
    const Answer p = probeExact(*moved);
    if (!hasError(p) && p.contains("hit") && !p["hit"].get<bool>()) return true;
  }
  return false;
}

/// Whether native's cast time keeps its guarantee (docs/narrowphase.md, "Shape casts"): never
/// later than exact's t, and the shapes placed at it within the contact tolerance δ =
/// kCastRelativeTolerance × S (S, the sizes plus the distance between the origins plus the
/// motion's length, is at most 4s + |motion| for a case of magnitude s) by exact distance, plus
/// the backend's own rounding. Along the motion such a t may lie further from exact's than δ: by
/// δ / cos of the approach angle.
bool castWithinContactTolerance(const DiffCase& c, const J& query, const J& got, const J& exact,
                                const WorldTolerance& tol, double s, const std::function<Answer(const DiffCase&)>& probeExact) {
  if (!got.contains("t") || !got["t"].is_number() || !exact["t"].is_number() || !query.contains("motion")) return false;
  const double t = got["t"].get<double>();
  if (t > exact["t"].get<double>()) return false;
  const V m = readV(query["motion"]);
  J a = query["a"];
  moveTransform(a["transform"], Vec3d(t * m[0], t * m[1], t * m[2]));
  DiffCase at = c;
  at.op = "distance";
  at.query = J{{"op", "distance"}, {"a", a}, {"b", query["b"]}}.dump();
  const Answer d = probeExact(at);
  if (hasError(d) || !d.contains("distance")) return false;
  return d["distance"].get<double>() <= kCastRelativeTolerance * (4 * s + motionLength(query)) + tol.at(s);
}


/// Scales every length of a query by `f` (in place): points, centres, radii, half extents,
/// translations, plane offsets, margins; not rotations, axes, directions or normals.
void scaleLengths(J& j, double f) {
  if (j.is_number()) {
    j = j.get<double>() * f;
  } else if (j.is_array()) {
    for (J& e : j) scaleLengths(e, f);
  } else if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      if (it.key() != "rotation" && it.key() != "axes" && it.key() != "dir" && it.key() != "normal" && it.key() != "id")
        scaleLengths(it.value(), f);
  }
}

/// Bullet's answer depends on the case's scale alone: the case (no setup lines; `contacts` and
/// the triangle–shape ops) scaled by 2^−k, k = ⌊log2 s⌋ ≥ 10 (coordinates ~1), is answered as
/// exact answers it. Scaling by a power of two is exact in float and commutes with every
/// rounded operation, so only Bullet's absolute constants (btGjkPairDetector's REL_ERROR2 = 1e-6
/// on the squared closest-point length, gGjkEpaPenetrationTolerance, btGjkEpa2's GJK_MIN_DISTANCE
/// and EPA_ACCURACY of 1e-4) tell the two apart: at coordinates ~1e6, GJK's float simplex leaves
/// the origin's closest point at rounding distance (~1e6 × 1.2e-7 = 0.1) from the origin, above
/// those constants, and Bullet reports the crossing shapes separated by it.
bool bulletRightWhenScaledDown(const DiffCase& c, const J& query, double s, const WorldTolerance& tol,
                               const WorldTolerance& exactTol, const std::function<Answer(const DiffCase&)>& probeExact,
                               const std::function<Answer(const DiffCase&)>& probePeer) {
  if (!probePeer || !c.setup.empty() || !(s >= 1024)) return false;
  if (c.op != "contacts" && !startsWith(c.op, "triangle_")) return false;
  const double f = std::ldexp(1.0, -int(std::floor(std::log2(s))));
  DiffCase scaled = c;
  J q = query;
  scaleLengths(q, f);
  scaled.query = q.dump();
  const Answer exact = probeExact(scaled), got = probePeer(scaled);
  if (hasError(exact) || hasError(got)) return false;
  const double small = s * f;
  const double numTol = tol.at(small) + exactTol.at(small) + (isNarrowOp(c.op) ? kNarrowRelative * small : 0);
  return compareAnswers(c.op, q, got, exact, numTol) == Difference::None;
}

Classification classifyAnswer(const DiffCase& c, std::string_view backend, const Answer& got, const Answer& exact,
                              const WorldTolerance& tol, const WorldTolerance& exactTol,
                              const std::function<Answer(const DiffCase&)>& probeExact,
                              const std::function<Answer(const DiffCase&)>& probePeer) {
  const std::string exactError = errorText(exact), gotError = errorText(got);
  if (!exactError.empty()) {
    if (!gotError.empty() && !startsWith(exactError, "unsupported:") && !startsWith(gotError, "unsupported:"))
      return {Verdict::Agree, "", "both reject the input"};
    if (startsWith(gotError, "unsupported:")) return {Verdict::Unsupported, "", gotError};
    return {Verdict::NoArbiter, "", exactError};
  }
  if (!gotError.empty()) {
    if (startsWith(gotError, "unsupported:")) return {Verdict::Unsupported, "", gotError};
    if (backend != "native") {
      // "<backend> failed on <op>: ..." (crux::BackendFailure, or the worker process's end)
      const std::string failed = std::string(backend) + " failed on ";
      const std::string text = startsWith(gotError, "setup: ") ? gotError.substr(7) : gotError;
      if (startsWith(text, failed)) {
        const std::size_t colon = text.find(": ", failed.size());
        const std::string what = colon == std::string::npos ? std::string() : text.substr(colon + 2);
        const char* cause = startsWith(what, "timeout")                                   ? "timeout"
                            : startsWith(what, "SIG") || startsWith(what, "the worker") ? "crash"
                                                                                        : "exception";
        return {Verdict::PeerFailed, cause, gotError};
      }
    }
    return {backend == "native" ? Verdict::CruxWrong : Verdict::Error, "error-answer", gotError};
  }
  const J query = J::parse(c.query, nullptr, false);
  const double s = std::max(caseMagnitude(c), 1e-300);
  const bool narrow = isNarrowOp(c.op);
  // the narrow-phase ops' numbers: the narrow phase's relative bound on top of the declared tolerance
  const double tau = tol.at(s) + (narrow ? kNarrowRelative * s : 0);
  const double numTol = tau + exactTol.at(s);
  const Difference diff = compareAnswers(c.op, query, got, exact, numTol);
  bool onSphere = false;
  const std::string witness = narrow && diff == Difference::None ? witnessProblem(c, query, got, numTol, &onSphere) : "";
  if (diff == Difference::None && witness.empty()) return {Verdict::Agree, "", ""};
  const bool native = backend == "native";
  std::ostringstream detail;
  detail << std::setprecision(17) << backend << " " << got.dump() << " vs exact " << exact.dump();
  if (diff == Difference::Shape) return {native ? Verdict::CruxWrong : Verdict::Error, "answer-shape", detail.str()};
  if (!witness.empty()) {
    // the distance agrees but its points are not a witness of it: no tolerance probe rescues that
    detail << "; witness: " << witness;
    if (native) return {Verdict::CruxWrong, "witness-off-shape", detail.str()};
    // FCL computes no nearest points for shapes in collision: penetrating convex pairs, and mesh
    // pairs that touch or cross (exact distance 0), get points of some colliding triangle pair
    const bool fclPenetrating =
        backend == "fcl" && (narrowNumber(c.op, exact) < 0 || (isMeshPairDistance(c.op) && narrowNumber(c.op, exact) == 0));
    return {Verdict::PeerWrong,
            fclPenetrating ? "nearest-points-in-collision"
            : backend == "fcl" && onSphere ? "sphere-local-point"
                                           : "witness-off-shape",
            detail.str()};
  }
  const bool boolean = diff == Difference::Boolean || diff == Difference::List;
  if (native && c.exactGrid && boolean) return {Verdict::CruxWrong, "grid-exactness", detail.str()};
  if (native && c.op == "cast" && diff == Difference::Numeric && castWithinContactTolerance(c, query, got, exact, tol, s, probeExact))
    return {Verdict::WithinTolerance, "cast-tolerance", detail.str()};
  if (!native && tol.minFeature > 0 && std::min(c.featureSize, smallestShape(query)) < tol.minFeature)
    return {Verdict::WithinTolerance, "below-min-feature", detail.str()};
  if (diff == Difference::Numeric && c.op == "ray_triangle" && rayHitOnMovedTriangle(query, got, tau, numTol))
    return {Verdict::WithinTolerance, "grazing-ray", detail.str()};
  if (diff == Difference::Numeric && c.op == "mesh_ray" && meshRayHitOnMovedTriangle(c, query, got, exact, tau, numTol))
    return {Verdict::WithinTolerance, "grazing-ray", detail.str()};
  const bool within = probeFlips(c, query, exact, got, tau, numTol, probeExact, true);
  if (native) return {within ? Verdict::WithinTolerance : Verdict::CruxWrong, within ? "boundary" : "beyond-tolerance", detail.str()};

  // a peer: the likely cause, most specific rule first (also recorded for disagreements within
  // tolerance, whose cause is "boundary" when no specific rule applies)
  const auto tris = caseTriangles(c, query);
  const bool bullet = backend == "bullet", fcl = backend == "fcl";
  const Verdict verdict = within ? Verdict::WithinTolerance : Verdict::PeerWrong;
  auto peer = [&](const char* cause) { return Classification{verdict, cause, detail.str()}; };
  if (c.op == "cast") {
    // the shapes touch or overlap at the start (exact: t = 0; for spheres and capsules, whose t
    // exact leaves open, their exact distance at the start): Bullet's sweeps report nothing, or a
    // later contact, for such a pair (oracle/README.md)
    bool startsTouching = exact.value("hit", false) && exact.contains("t") && exact["t"].is_number() &&
                          exact["t"].get<double>() == 0;
    if (exact.value("hit", false) && exact.contains("t") && exact["t"].is_null()) {
      DiffCase atStart = c;
      atStart.op = "distance";
      atStart.query = J{{"op", "distance"}, {"a", query["a"]}, {"b", query["b"]}}.dump();
      const Answer d = probeExact(atStart);
      startsTouching = !hasError(d) && d.contains("distance") && d["distance"].get<double>() <= 0;
    }
    if (startsTouching) return peer("cast-start");
    const auto rounded = [&](const char* key) {
      return query[key].contains("sphere") || query[key].contains("capsule");
    };
    // FCL's advancement steps past some sphere and capsule contacts (oracle/README.md)
    if (fcl && diff == Difference::Boolean && exact.value("hit", false) && (rounded("a") || rounded("b")))
      return peer("cast-rounded-miss");
    if (degenerateOperand(query)) return peer("degenerate-shape");
    // the fcl world casts a triangle as a one-face fcl::Convex (FCL has no advancement for
    // TriangleP): a flat shape, whose casts FCL sometimes ends late, well inside it
    if (fcl && (query["a"].contains("triangle") || query["b"].contains("triangle"))) return peer("flat-shape");
    if (within) return peer("boundary");
    // the shapes only graze (b moved by up to 1e-3 × s makes exact miss): the peers' absolute
    // tolerances lose or delay such contacts (libccd's 1e-6, Bullet's float GJK)
    if (onlyGrazes(c, exact, s, probeExact)) return peer("touching");
    if (diff == Difference::Numeric)  // both hit; t differs beyond the tolerance
      return peer(castTimeGap(query, got, exact) <= 1e-3 * std::max(s, 1.0) ? "precision" : "unexplained");
  }
  if (narrow) {
    const bool meshOperand = isMeshPairDistance(c.op) || query["a"].contains("mesh") || query["b"].contains("mesh");
    // FCL 0.7: a mesh (BVHModel) against a penetrating shape gets a bogus distance (docs/batch.md)
    // (the fcl world makes a triangle operand a one-triangle BVHModel: a mesh to FCL, whose
    // crossing mesh pairs answer 0, never a depth)
    const bool fclMesh = meshOperand || query["a"].contains("triangle") || query["b"].contains("triangle");
    if (fcl && c.op == "distance" && fclMesh && narrowNumber(c.op, exact) < 0) return peer("mesh-penetration");
    // Bullet's contactPairTest: one unreduced point per touching triangle, internal-edge
    // (ghost) contacts with their own normals and depths
    if (bullet && c.op == "contacts" && meshOperand && diff == Difference::Numeric) return peer("ghost-contacts");
    if (degenerateOperand(query)) return peer("degenerate-shape");
    // exact's nearest triangle pair includes a collinear or repeated-corner triangle
    if (exactWitnessOnDegenerateTriangle(c, query, exact)) return peer("degenerate-triangle");
    // Bullet misses a contact that exact finds deepest on a degenerate mesh triangle
    if (bullet && diff == Difference::Boolean && !narrowVerdict(c.op, got) && exactContactOnDegenerateTriangle(c, query, exact))
      return peer("degenerate-triangle");
    // FCL's nearest triangle of a mesh operand is degenerate: its distance there is 0, garbage points
    if (fcl && peerWitnessOnDegenerateTriangle(c, query, got)) return peer("degenerate-triangle");
    // Bullet's sphere–triangle detector skips a triangle whose float normal is below FLT_EPSILON
    if (bullet && c.op == "contacts" && diff == Difference::Boolean && !narrowVerdict(c.op, got) &&
        sphereTriangleFloatNormalTooSmall(query))
      return peer("sphere-triangle-small-normal");
    if (thinnerThan(caseTriangles(c, query), tau)) return peer("sliver-triangle");
    if (within) return peer("boundary");
    // a sphere or capsule whose core (centre, segment) touches the other shape (exact depth = its
    // radius): Bullet's GJK/EPA sees it as the core with the radius as margin, and EPA on a
    // Minkowski difference with the origin on its boundary returns an imprecise normal and depth,
    // or no contact
    if (bullet && c.op == "contacts" && narrowVerdict(c.op, exact)) {
      for (const char* side : {"a", "b"})
        for (const char* rounded : {"sphere", "capsule"})
          if (query[side].contains(rounded) &&
              std::fabs(narrowNumber(c.op, exact) - query[side][rounded]["radius"].get<double>()) <= tau)
            return peer("core-on-surface");
    }
    // Bullet answers the same case scaled down by a power of two right: its absolute epsilons
    // (before the symmetric boxes, which Bullet then gets right at the smaller scale)
    if (bullet && bulletRightWhenScaledDown(c, query, s, tol, exactTol, probeExact, probePeer))
      return peer("absolute-epsilons");
    // Bullet's GJK stopped on a rejected simplex and reported its previous closest point
    if (bullet && c.op == "contacts" && (diff == Difference::Numeric || !narrowVerdict(c.op, got)) &&
        bulletGjkStoppedEarly(c, query, got, exact, s, numTol, probePeer))
      return peer("gjk-early-stop");
    // boxes whose Minkowski difference is mirror-symmetric about a plane through the origin:
    // Bullet's EPA ends on a face inside it, its depth short
    // (or no contact at all: a depth at rounding level of 0 comes out as a separation)
    if (bullet && c.op == "contacts" && (diff == Difference::Numeric || !narrowVerdict(c.op, got)) &&
        boxesMirrorSymmetric(query, numTol))
      return peer("epa-symmetric-boxes");
    // Bullet's EPA stopped early (InvalidHull) and reported an inner face of its polytope
    if (bullet && c.op == "contacts" && diff == Difference::Numeric && narrowNumber(c.op, got) < narrowNumber(c.op, exact) &&
        bulletEpaInnerFace(query, got, numTol))
      return peer("epa-inner-face");
    // shapes that touch (exact distance within τ of 0): libccd's GJK, with its absolute 1e-6
    // tolerance, declares them colliding, and its EPA, run on a Minkowski difference with the
    // origin on its boundary, reports a depth that is not there
    if (fcl && c.op == "distance" && std::fabs(narrowNumber(c.op, exact)) <= tau && narrowNumber(c.op, got) < -tau)
      return peer("touching-depth");
    // separated polytopes whose GJK stopped on a support point as far from the origin as its
    // current closest point (libccd's equal-norm stop)
    if (fcl && c.op == "distance" && narrowNumber(c.op, exact) > tau &&
        narrowNumber(c.op, got) > narrowNumber(c.op, exact) &&
        (fclGjkStoppedOnEqualNorm(c, query, got, numTol) ||
         fclMeshTriangleStoppedOnEqualNorm(c, query, got, exact, numTol, probePeer)))
      return peer("gjk-equal-norm-stop");
    // penetrating polytopes whose GJK ended on a segment through the origin: libccd's EPA takes
    // it for a touching contact (a support point equal to a segment end) and answers depth 0
    if (fcl && c.op == "distance" && narrowNumber(c.op, exact) < -tau && fclEpaTouchingOnGjkSegment(query, got, numTol))
      return peer("epa-segment-touching");
    if (diff == Difference::Numeric) {
      const double worst = std::fabs(narrowNumber(c.op, got) - narrowNumber(c.op, exact));
      return peer(worst <= 1e-3 * std::max(s, 1.0) ? "precision" : "unexplained");
    }
    if (probeFlips(c, query, exact, got, 1e-3 * s, numTol, probeExact, false)) return peer("touching");
    if (bullet && probeFlips(c, query, exact, got, 0.04, numTol, probeExact, false)) return peer("margin");
    return peer("unexplained");
  }
  // the point on the triangle: exact's closest point is the point itself, up to exact's one
  // rounding of the result (within τ; a corner 1.4e-45 off the grid puts an edge's midpoint 2e-15
  // from its rounded closest point), and FCL, seeing a collision, computes no nearest point
  if (fcl && c.op == "closest_point_triangle" && query.contains("point") &&
      maxDiff(exact["point"], query["point"]) <= tau)
    return peer("nearest-points-in-collision");
  if (bullet && isRayOrSegmentOp(c.op) && endpointOnPlane(query, tris)) return peer("plane-endpoint");
  // the same on a placed model's triangle: Bullet tests the ray moved into the model's frame in
  // float (btCollisionWorld::rayTestSingle), where the endpoint lands on the triangle's plane (seed
  // 9001 case 30028, a quarter turn: exactly) or within rounding of it, on either side
  if (bullet && isRayOrSegmentOp(c.op) && endpointOnPlane(query, rayModelTriangles(c, query, got, exact)))
    return peer("plane-endpoint");
  // Bullet's broad phase culls the model exact hits: the ray lies in its unpadded box's face plane
  if (bullet && bulletBroadphaseCullsModel(c, query, got, exact)) return peer("broadphase-face-ray");
  // Bullet hits a triangle whose plane the segment crosses only in its float arithmetic
  if (bullet && isRayOrSegmentOp(c.op) && diff == Difference::Boolean && got.value("hit", false)) {
    const BulletFloatRay wrong = bulletFloatRaycast(c.op, query, tris);
    if (wrong == BulletFloatRay::Side) return peer("float-plane-side");
    // Bullet's float crossing point of a ray grazing the plane lands inside the fattened edges
    if (wrong == BulletFloatRay::Crossing) return peer("float-crossing-point");
  }
  // Bullet hits a triangle whose plane the ray or segment crosses just outside it
  if (bullet && isRayOrSegmentOp(c.op) && diff == Difference::Boolean && got.value("hit", false) &&
      withinFattenedEdges(query, tris))
    return peer("fattened-edges");
  for (const auto& t : caseTriangles(c, query, true))
    if (degenerate(t)) return peer("degenerate-triangle");
  if (thinnerThan(caseTriangles(c, query, true), tau)) return peer("sliver-triangle");
  bool pointSphere = false;
  if (flatShape(query, &pointSphere)) return peer(bullet && pointSphere ? "point-sphere" : "flat-shape");
  if (bullet && (c.op == "mesh_mesh" || c.op == "scene_pairs") && diff == Difference::Boolean &&
      got["hit"].get<bool>())
    return peer("gimpact-triangle-pairs");
  if (bullet && c.op == "scene_pairs") {
    // pairs only bullet reports: GImpact's triangle-pair test
    std::set<J> e(exact["pairs"].begin(), exact["pairs"].end());
    for (const auto& p : got["pairs"])
      if (!e.count(p)) return peer("gimpact-triangle-pairs");
  }
  if (within) return peer("boundary");
  // A peer's hit on shapes within τ of each other, though no probe flips exact's miss: the gap is
  // below an ulp of the coordinates, so a probe's offset vanishes when the moved case is parsed
  // into Real (a triangle 1e-7 from a plane at coordinates ~8, in a float build). The peer's
  // hit is within its declared tolerance.
  if (diff == Difference::Boolean && got.value("hit", false) && !exact.value("hit", true) && caseGap(c, query) <= tau)
    return {Verdict::WithinTolerance, "boundary", detail.str()};
  // Bullet's earlier hit is on a mesh triangle the ray passes just outside (its fattened edges):
  // the triangle Bullet names, placed as the query places the mesh
  if (bullet && (c.op == "mesh_ray" || c.op == "mesh_segment") && diff == Difference::Numeric && got.value("hit", false) &&
      got.contains("triangle") && got["triangle"].is_number_integer() && got["triangle"].get<long long>() >= 0) {
    const auto placed = placedQueryTriangles(c, query);
    const auto k = got["triangle"].get<std::size_t>();
    if (k < placed.size()) {
      const std::array<V, 3> t = {V{placed[k][0].x(), placed[k][0].y(), placed[k][0].z()},
                                  V{placed[k][1].x(), placed[k][1].y(), placed[k][1].z()},
                                  V{placed[k][2].x(), placed[k][2].y(), placed[k][2].z()}};
      if (withinFattenedEdges(query, {t})) return peer("fattened-edges");
    }
  }
  if (diff == Difference::Numeric) {
    // both found a contact; the numbers differ beyond the declared tolerance
    double worst = maxDiff(got["point"], exact["point"]);
    if (got.contains("t")) worst = std::max(worst, std::fabs(got["t"].get<double>() - exact["t"].get<double>()));
    return peer(worst <= 1e-3 * std::max(s, 1.0) ? "precision" : "unexplained");
  }
  if (probeFlips(c, query, exact, got, 1e-3 * s, numTol, probeExact, false)) return peer("touching");
  if (diff == Difference::Boolean && exact.value("hit", false) && meshOnlyTouches(c, query, tau, probeExact))
    return peer("touching");
  if (bullet && probeFlips(c, query, exact, got, 0.04, numTol, probeExact, false)) return peer("margin");
  if (bullet && c.op == "mesh_mesh") return peer("gimpact-miss");
  // Bullet's GJK (btGjkEpa2) stopped on a support point it had seen and dropped: crossing
  // triangles come out apart
  if (bullet && diff == Difference::Boolean && exact.value("hit", false) &&
      bulletTrianglesApartOnAnUnfinishedGjk(c, query, s, numTol, probePeer))
    return peer("gjk-duplicate-stop");
  if (bullet && bulletRightWhenScaledDown(c, query, s, tol, exactTol, probeExact, probePeer))
    return peer("absolute-epsilons");
  // Bullet's GJK on each mesh triangle the query crosses stopped early (btGjkPairDetector)
  if (bullet && diff == Difference::Boolean && !got.value("hit", true) &&
      bulletMeshTrianglesApartOnAnEarlyGjkStop(c, query, exact, s, numTol, probeExact, probePeer))
    return peer("gjk-early-stop");
  return peer("unexplained");
}

// ---- shrinking -----------------------------------------------------------------------------------

namespace {

/// Candidate simpler values for a number, simplest first.
std::vector<double> simpler(double x, bool keepGrid) {
  std::vector<double> out;
  if (x == 0) return out;
  out.push_back(0);
  const double r = std::round(x);
  if (r != x) out.push_back(r);
  for (int bits : {4, 12}) {
    int e = 0;
    const double m = std::frexp(x, &e);
    const double rounded = std::ldexp(std::round(std::ldexp(m, bits)), e - bits);
    if (rounded != x && rounded != r) out.push_back(rounded);
  }
  const double half = x / 2;
  if (!keepGrid || half == std::round(half)) out.push_back(half);
  return out;
}

/// JSON pointers of the numbers of `j` that shrinking may change.
void numberPaths(const J& j, const J::json_pointer& at, const std::string& key, std::vector<J::json_pointer>& out) {
  if (key == "rotation" || key == "triangles" || key == "axes") return;
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) numberPaths(*it, at / it.key(), it.key(), out);
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) numberPaths(j[i], at / i, key, out);
  } else if (j.is_number()) {
    out.push_back(at);
  }
}

/// Removes vertices no triangle uses (renumbering the triangles).
void compactMesh(J& m) {
  std::vector<int> remap(m["vertices"].size(), -1);
  J vs = J::array();
  for (auto& t : m["triangles"])
    for (auto& i : t) {
      const std::size_t v = i.get<std::size_t>();
      if (remap[v] < 0) {
        remap[v] = int(vs.size());
        vs.push_back(m["vertices"][v]);
      }
      i = remap[v];
    }
  m["vertices"] = vs;
}

}  // namespace

DiffCase shrinkCase(const DiffCase& c, const Classification& target,
                    const std::function<std::optional<Classification>(const DiffCase&)>& classify, int budget) {
  DiffCase best = c;
  int used = 0;
  auto keeps = [&](const DiffCase& candidate) {
    if (used >= budget) return false;
    ++used;
    const auto k = classify(candidate);
    return k && *k == target;
  };
  // 1. setup lines
  if (!best.sharedSetup) {
    for (std::size_t i = best.setup.size(); i-- > 0;) {
      DiffCase t = best;
      t.setup.erase(t.setup.begin() + std::ptrdiff_t(i));
      if (keeps(t)) best = t;
    }
  }
  // 2. triangles of small meshes
  for (std::size_t li = 0; li < best.setup.size(); ++li) {
    J m = J::parse(best.setup[li], nullptr, false);
    if (!m.is_object() || m.value("op", "") != "mesh" || m["triangles"].size() > 64) continue;
    for (std::size_t ti = m["triangles"].size(); ti-- > 0 && m["triangles"].size() > 1;) {
      J reduced = m;
      reduced["triangles"].erase(ti);
      DiffCase t = best;
      t.setup[li] = reduced.dump();
      if (keeps(t)) {
        best = t;
        m = reduced;
      }
    }
    compactMesh(m);
    DiffCase t = best;
    t.setup[li] = m.dump();
    if (keeps(t)) best = t;
  }
  // 3. numbers: the query's and the setup's (vertices, translations)
  for (int pass = 0; pass < 3; ++pass) {
    bool changed = false;
    for (int line = -1; line < int(best.setup.size()); ++line) {
      if (line >= 0 && best.sharedSetup) break;
      J doc = J::parse(line < 0 ? best.query : best.setup[std::size_t(line)], nullptr, false);
      std::vector<J::json_pointer> paths;
      numberPaths(doc, J::json_pointer(), "", paths);
      for (const auto& p : paths) {
        for (const double v : simpler(doc[p].get<double>(), best.exactGrid)) {
          J edited = doc;
          edited[p] = (v == std::trunc(v) && std::fabs(v) < 1e15) ? J(std::int64_t(v)) : J(v);
          DiffCase t = best;
          (line < 0 ? t.query : t.setup[std::size_t(line)]) = edited.dump();
          if (keeps(t)) {
            best = t;
            doc = edited;
            changed = true;
            break;
          }
        }
      }
    }
    if (!changed) break;
  }
  return best;
}

// ---- the run -------------------------------------------------------------------------------------

namespace {

const std::vector<std::string> kVerdictColumns = {"agree",       "within_tolerance", "peer_wrong", "crux_wrong",
                                                  "unsupported", "error",            "no_arbiter", "peer_failed"};

std::vector<std::string> allQueryOps() {
  std::vector<std::string> ops;
  for (const auto f : diffFamilies())
    for (const auto op : diffFamilyOps(f))
      if (std::find(ops.begin(), ops.end(), op) == ops.end()) ops.emplace_back(op);
  return ops;
}

/// Writes a case as protocol JSON Lines (the query carries "id": name) and its sidecar.
void writeCase(const std::string& dir, const std::string& name, const DiffCase& c, const Answer& meta) {
  std::filesystem::create_directories(dir);
  std::ofstream lines(dir + "/" + name + ".jsonl");
  for (const auto& l : c.setup) lines << l << '\n';
  J q = J::parse(c.query);
  J withId = J{{"id", name}};
  for (auto it = q.begin(); it != q.end(); ++it) withId[it.key()] = *it;
  lines << withId.dump() << '\n';
  std::ofstream side(dir + "/" + name + ".json");
  side << meta.dump(2) << '\n';
}

}  // namespace

Answer DiffSummary::toJson() const {
  J j = J::object();
  j["seed"] = seed;
  j["first_case"] = firstCase;
  j["requested_cases"] = requestedCases;
  j["families"] = families;
  j["ops"] = ops;
  j["backends"] = backends;
  j["shrink_per_kind"] = shrinkPerKind;
  j["cases"] = cases;
  j["seconds"] = seconds;
  J t = J::object();
  for (const auto& [op, perBackend] : table) {
    J row = J::object();
    for (const auto& [backend, counts] : perBackend) {
      J cell = J::object();
      for (const auto& [verdict, n] : counts) cell[verdict] = n;
      row[backend] = cell;
    }
    t[op] = row;
  }
  j["table"] = t;
  J causes = J::object();
  for (const auto& [backend, m] : peerCauses) causes[backend] = J(m);
  j["peer_causes"] = causes;
  J tcauses = J::object();
  for (const auto& [backend, m] : toleranceCauses) tcauses[backend] = J(m);
  j["within_tolerance_causes"] = tcauses;
  J failures = J::object();
  for (const auto& [backend, m] : peerFailures) failures[backend] = J(m);
  j["peer_failures"] = failures;
  j["crux_wrong"] = cruxWrong;
  j["findings"] = J(findings);
  j["error_examples"] = J(exampleErrors);
  j["error_example_cases"] = J(exampleErrorCases);
  return j;
}

void DiffSummary::print(std::ostream& out) const {
  std::set<std::string> backends;
  for (const auto& [op, perBackend] : table)
    for (const auto& [b, counts] : perBackend) backends.insert(b);
  out << "crux diff: " << cases << " cases in " << std::fixed << std::setprecision(1) << seconds << " s\n";
  out << "per op x backend (exact: answered / - / - / - / unsupported / error): agree / within tolerance / peer wrong / crux wrong / unsupported / error / no arbiter / peer failed\n";
  out << std::left << std::setw(24) << "op";
  for (const auto& b : backends) out << std::setw(30) << b;
  out << '\n';
  for (const auto& [op, perBackend] : table) {
    out << std::setw(24) << op;
    for (const auto& b : backends) {
      std::string cell;
      const auto it = perBackend.find(b);
      for (const auto& v : kVerdictColumns) {
        const std::uint64_t n = it == perBackend.end() || !it->second.count(v) ? 0 : it->second.at(v);
        cell += (cell.empty() ? "" : "/") + (n ? std::to_string(n) : std::string("-"));
      }
      out << std::setw(30) << cell;
    }
    out << '\n';
  }
  for (const auto& [title, m] : {std::pair{"peer wrong, by likely cause", &peerCauses},
                                 std::pair{"within tolerance, by reason", &toleranceCauses},
                                 std::pair{"peer failed (threw, crashed or timed out)", &peerFailures}}) {
    if (m->empty()) continue;
    out << title << ":\n";
    for (const auto& [backend, causes] : *m)
      for (const auto& [cause, n] : causes) out << "  " << std::setw(8) << backend << std::setw(30) << cause << n << '\n';
  }
  if (!exampleErrors.empty()) {
    out << "error answers (first of each backend.op):\n";
    for (const auto& [where, text] : exampleErrors) out << "  " << where << ": " << text.substr(0, 400) << '\n';
  }
  out << "crux wrong: " << cruxWrong << '\n';
  out << std::right;
}

DiffSummary runDiff(const DiffOptions& options, std::ostream& err) {
  // options
  std::vector<std::string> families = options.families;
  if (families.empty())
    for (const auto f : diffFamilies()) families.emplace_back(f);
  for (const auto& f : families)
    if (std::find(diffFamilies().begin(), diffFamilies().end(), f) == diffFamilies().end())
      throw InvalidInput("families: unknown family \"" + f + "\"");
  const std::vector<std::string> queryOps = allQueryOps();
  for (const auto& op : options.ops)
    if (std::find(queryOps.begin(), queryOps.end(), op) == queryOps.end())
      throw InvalidInput("ops: \"" + op + "\" is not a query op the fuzzer generates");
  std::vector<std::string> backends = options.backends;
#ifdef CRUX_DIFF_HAVE_ORACLE
  if (backends.empty())
    for (const auto b : builtBackends()) backends.emplace_back(b);
  for (const auto& b : backends) {
    const auto& built = builtBackends();
    if (std::find(built.begin(), built.end(), b) == built.end())
      throw InvalidInput("backends: \"" + b + "\" is not a backend built into this crux");
  }
  if (std::find(builtBackends().begin(), builtBackends().end(), "exact") == builtBackends().end())
    throw InvalidInput("backends: the exact backend (the arbiter) is not built");
#else
  throw InvalidInput("backends: crux was built without the oracle backends (CRUX_BUILD_ORACLE)");
#endif
  backends.erase(std::remove(backends.begin(), backends.end(), "exact"), backends.end());
  bool anyOp = false;
  DiffGenerator generator;
  generator.meshDir = options.meshDir;
  generator.ops = options.ops;
  for (const auto& f : families)
    for (const auto op : diffFamilyOps(f))
      anyOp = anyOp || options.ops.empty() || std::find(options.ops.begin(), options.ops.end(), op) != options.ops.end();
  if (!anyOp) throw InvalidInput("ops: no selected family generates any of the selected ops");

  DiffRunner runner(options.workerExecutable, options.peerTimeoutSeconds);
  const WorldTolerance exactTol = runner.tolerance("exact");
  DiffSummary summary;
  std::map<std::string, int> written;  // shrunk cases per (backend, op, verdict, cause)
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  double lastDraw = -1;
  summary.seed = options.seed;
  summary.firstCase = options.firstCase;
  summary.requestedCases = options.seconds > 0 ? 0 : options.cases;
  summary.families = families;
  summary.ops = options.ops;
  summary.backends = backends;
  summary.shrinkPerKind = options.shrinkPerKind;
  for (std::uint64_t index = options.firstCase;; ++index) {
    if (options.seconds > 0 ? elapsed() >= options.seconds : index >= options.firstCase + options.cases) break;
    const std::string& family = families[index % families.size()];
    const auto generated = generateCase(family, options.seed, index, generator);
    if (!generated) continue;
    const DiffCase& c = *generated;
    ++summary.cases;
    std::map<std::string, Answer> probeCache;
    auto probeExact = [&](const DiffCase& moved) {
      std::string key = moved.query;
      for (const auto& l : moved.setup) key += "\n" + l;
      auto it = probeCache.find(key);
      if (it == probeCache.end()) it = probeCache.emplace(key, runner.run(moved, "exact")).first;
      return it->second;
    };
    const Answer exact = runner.run(c, "exact");
    {
      const std::string e = errorText(exact);
      ++summary.table[c.op]["exact"][e.empty() ? "agree" : startsWith(e, "unsupported:") ? "unsupported" : "error"];
      if (!e.empty() && !summary.exampleErrors.count("exact." + c.op)) {
        summary.exampleErrors["exact." + c.op] = e + " <- " + c.query;
        summary.exampleErrorCases["exact." + c.op] = c.index;
      }
    }
    // Narrow-phase ops on a build whose exact backend does not answer them: native is the
    // reference for the peers (and has no arbiter itself).
    const bool nativeReference = isNarrowOp(c.op) && startsWith(errorText(exact), "unsupported:");
    const Answer reference = nativeReference ? runner.run(c, "native") : exact;
    auto probeNative = [&](const DiffCase& moved) { return runner.run(moved, "native"); };
    for (const auto& backend : backends) {
      const WorldTolerance tol = runner.tolerance(backend);
      const Answer got = runner.run(c, backend);
      auto probePeer = [&](const DiffCase& other) { return runner.run(other, backend); };
      const Classification k =
          !nativeReference ? classifyAnswer(c, backend, got, exact, tol, exactTol, probeExact, probePeer)
          : backend == "native"
              ? Classification{Verdict::NoArbiter, "", errorText(exact)}
              : classifyAnswer(c, backend, got, reference, tol, runner.tolerance("native"), probeNative);
      ++summary.table[c.op][backend][std::string(verdictName(k.verdict))];
      if (k.verdict == Verdict::PeerWrong) ++summary.peerCauses[backend][k.cause];
      if (k.verdict == Verdict::WithinTolerance) ++summary.toleranceCauses[backend][k.cause];
      if (k.verdict == Verdict::PeerFailed) ++summary.peerFailures[backend][k.cause];
      if (k.verdict == Verdict::CruxWrong) ++summary.cruxWrong;
      if ((k.verdict == Verdict::Error || k.verdict == Verdict::PeerFailed) &&
          !summary.exampleErrors.count(backend + "." + c.op)) {
        summary.exampleErrors[backend + "." + c.op] = k.detail + " <- " + c.query;
        summary.exampleErrorCases[backend + "." + c.op] = c.index;
      }
      const bool interesting = k.verdict == Verdict::CruxWrong || k.verdict == Verdict::PeerWrong;
      if (!interesting) continue;
      const std::string kind = backend + "." + (k.verdict == Verdict::CruxWrong ? "crux-wrong" : k.cause) + "." + c.op;
      if (written[kind] >= options.shrinkPerKind) continue;
      ++written[kind];
      // shrink: same verdict and cause on a smaller case
      auto reclassify = [&](const DiffCase& t) -> std::optional<Classification> {
        std::map<std::string, Answer> cache;
        auto probe = [&](const DiffCase& moved) { return runner.run(moved, "exact"); };
        const Answer e = runner.run(t, "exact");
        const Answer g = runner.run(t, backend);
        (void)cache;
        return classifyAnswer(t, backend, g, e, tol, exactTol, probe, probePeer);
      };
      // Peer findings of the narrow-phase ops stay unshrunk: the shrinker's snapped numbers make
      // degenerate simplices on which FCL 0.7's libccd GJK aborts (assertion "A is not in region
      // 1" in doSimplex2) or loops: a worker restart or the whole time limit per shrink step (and
      // the end of the process for a runner without workers).
      const bool shrink = !(isNarrowOp(c.op) && backend != "native");
      const DiffCase small = shrink ? shrinkCase(c, k, reclassify, c.sharedSetup ? 60 : 300) : c;
      const Answer smallExact = runner.run(small, "exact"), smallGot = runner.run(small, backend);
      const std::string name = kind + "." + std::to_string(c.seed) + "-" + std::to_string(c.index);
      J meta = J{{"name", name},         {"kind", kind},
                 {"family", c.family},
                 {"seed", c.seed},       {"index", c.index},
                 {"op", c.op},           {"backend", backend},
                 {"verdict", std::string(verdictName(k.verdict))},
                 {"cause", k.cause},     {"exact_grid", small.exactGrid},
                 {"exact", smallExact},  {backend, smallGot},
                 {"original_detail", k.detail}};
      summary.findings.push_back(meta);
      if (!options.outDir.empty()) writeCase(options.outDir, name, small, meta);
      if (k.verdict == Verdict::CruxWrong) {
        err << "crux diff: CRUX WRONG (" << k.cause << ") family " << c.family << " case " << c.index << ": "
            << k.detail << "\n  minimal case:\n";
        for (const auto& l : small.setup) err << "  " << l << '\n';
        err << "  " << small.query << '\n';
      }
    }
    if (options.progress && elapsed() - lastDraw > 0.25) {
      lastDraw = elapsed();
      std::uint64_t peer = 0;
      for (const auto& [b, m] : summary.peerCauses)
        for (const auto& [cause, n] : m) peer += n;
      err << "\r" << summary.cases;
      if (options.seconds <= 0) err << "/" << options.cases;
      err << " cases  " << std::fixed << std::setprecision(0) << double(summary.cases) / std::max(elapsed(), 1e-9)
          << " cases/s  peer wrong " << peer << "  crux wrong " << summary.cruxWrong << "   " << std::flush;
    }
  }
  if (options.progress) err << '\n';
  summary.seconds = elapsed();
  return summary;
}

void writeJsonFile(const std::string& path, const Answer& json) {
  const std::string temporary = path + ".partial";
  {
    std::ofstream out(temporary);
    out << json.dump(2) << '\n';
    if (!out) throw InvalidInput("json: cannot write \"" + temporary + "\"");
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) throw InvalidInput("json: cannot write \"" + path + "\"");
}

int runDiffCommand(const DiffOptions& options, std::ostream& out, std::ostream& err) {
  DiffOptions run = options;
  if (!options.shardDir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.shardDir, ec);
    if (ec) throw InvalidInput("shard-dir: cannot create \"" + options.shardDir + "\": " + ec.message());
    if (run.outDir.empty()) run.outDir = options.shardDir + "/findings";
    if (run.jsonFile.empty()) run.jsonFile = options.shardDir + "/summary.json";
    std::filesystem::remove(options.shardDir + "/summary.json", ec);  // a rerun replaces the shard
    writeJsonFile(options.shardDir + "/started.json",
                  J{{"seed", options.seed}, {"first_case", options.firstCase},
                    {"requested_cases", options.seconds > 0 ? 0 : options.cases}});
  }
  const DiffSummary summary = runDiff(run, err);
  if (!run.quiet) summary.print(out);
  if (!run.jsonFile.empty()) writeJsonFile(run.jsonFile, summary.toJson());
  return summary.cruxWrong > 0 ? 1 : 0;
}

}  // namespace crux::cli
