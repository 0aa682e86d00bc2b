/// @file diff_generate.cpp  Case generation of `crux diff`: the families of docs/diff.md.
///
/// Every number a case holds is representable as a float (so float and double builds, and all
/// backends, read the same values). Contacts in the grid families are built exactly (a vertex at
/// an extreme of the other shape, a plane through an extreme vertex, a triangle whose other
/// corners lie on one side of the first one's plane), so touching cases really touch.

#include "cli/diff.hpp"

#include <crux/error.hpp>
#include <crux/mesh/mesh.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>

namespace crux::cli {
namespace {

using V = std::array<double, 3>;
using J = Answer;

V add(V a, V b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
V sub(V a, V b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V mul(V a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(V a, V b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V cross(V a, V b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
bool isZero(V a) { return a[0] == 0 && a[1] == 0 && a[2] == 0; }

/// SplitMix64 (Steele, Lea, Flood 2014): a fixed, portable generator, so cases do not depend
/// on the standard library's distributions.
struct Rng {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// Uniform in [lo, hi] (integers).
  int integer(int lo, int hi) { return lo + int(next() % std::uint64_t(hi - lo + 1)); }
  /// Uniform in [0, 1).
  double unit() { return double(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  bool chance(double p) { return unit() < p; }
  template <class T>
  const T& pick(const std::vector<T>& v) { return v[next() % v.size()]; }
  V gridPoint(int r) { return {double(integer(-r, r)), double(integer(-r, r)), double(integer(-r, r))}; }
  V floatPoint(double r) { return {uniform(-r, r), uniform(-r, r), uniform(-r, r)}; }
  V nonZeroGrid(int r) {
    for (;;) {
      V v = gridPoint(r);
      if (!isZero(v)) return v;
    }
  }
};

double toFloat(double x) { return double(float(x)); }
V toFloat(V v) { return {toFloat(v[0]), toFloat(v[1]), toFloat(v[2])}; }

/// A JSON number: integers as integers (so lines read naturally), others as doubles.
J num(double x) {
  if (x == std::trunc(x) && std::fabs(x) < 1e15) return J(std::int64_t(x));
  return J(x);
}
J vec(V v) { return J::array({num(v[0]), num(v[1]), num(v[2])}); }

// ---- shapes -------------------------------------------------------------------------------------

struct Tri {
  V a, b, c;
  V normal() const { return cross(sub(b, a), sub(c, a)); }
};
J triJson(const Tri& t) { return J::array({vec(t.a), vec(t.b), vec(t.c)}); }

/// A unit quaternion (w, x, y, z), uniform (Shoemake 1992).
std::array<double, 4> randomRotation(Rng& rng) {
  const double u1 = rng.unit(), u2 = rng.uniform(0, 2 * M_PI), u3 = rng.uniform(0, 2 * M_PI);
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  return {a * std::sin(u2), a * std::cos(u2), b * std::sin(u3), b * std::cos(u3)};
}
/// Rotation matrix (rows) of a unit quaternion.
std::array<V, 3> rotationMatrix(const std::array<double, 4>& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return {V{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
          V{2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
          V{2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
}
V apply(const std::array<V, 3>& m, V v) { return {dot(m[0], v), dot(m[1], v), dot(m[2], v)}; }

/// Rotations that map the integer grid onto itself, as quaternions and exact matrices:
/// identity, half turns and quarter turns about the axes (crux snaps the float-rounded
/// quarter-turn quaternions to the exact permutation; see include/crux/model/model_query.hpp).
struct GridRotation {
  std::array<double, 4> q;
  std::array<V, 3> m;
};
const std::vector<GridRotation>& gridRotations() {
  static const std::vector<GridRotation> rotations = [] {
    const double h = std::sqrt(0.5);
    std::vector<std::array<double, 4>> qs = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1},
                                             {h, h, 0, 0}, {h, 0, h, 0}, {h, 0, 0, h}, {h, -h, 0, 0},
                                             {h, 0, -h, 0}, {h, 0, 0, -h}};
    std::vector<GridRotation> out;
    for (const auto& q : qs) {
      auto m = rotationMatrix(q);
      for (auto& row : m)
        for (double& e : row) e = std::round(e);
      out.push_back({q, m});
    }
    return out;
  }();
  return rotations;
}

J rotationJson(const std::array<double, 4>& q) { return J::array({num(q[0]), num(q[1]), num(q[2]), num(q[3])}); }

/// Signed permutation frames (possibly left-handed) for grid OBBs: rows are the axes.
std::array<V, 3> gridFrame(Rng& rng) {
  std::array<int, 3> perm = {0, 1, 2};
  for (int i = 2; i > 0; --i) std::swap(perm[std::size_t(i)], perm[std::size_t(rng.integer(0, i))]);
  std::array<V, 3> axes{};
  for (std::size_t i = 0; i < 3; ++i) {
    axes[i] = {0, 0, 0};
    axes[i][std::size_t(perm[i])] = rng.chance(0.5) ? 1 : -1;
  }
  return axes;
}

J sphereJson(V c, double r) { return J{{"center", vec(c)}, {"radius", num(r)}}; }
J aabbJson(V lo, V hi) { return J{{"min", vec(lo)}, {"max", vec(hi)}}; }
J obbJson(V c, V half, const std::array<V, 3>& axes) {
  return J{{"center", vec(c)}, {"half", vec(half)}, {"axes", J::array({vec(axes[0]), vec(axes[1]), vec(axes[2])})}};
}
J planeJson(V n, double d) { return J{{"normal", vec(n)}, {"d", num(d)}}; }
J rayJson(V o, V d) { return J{{"origin", vec(o)}, {"dir", vec(d)}}; }
J segmentJson(V s, V e) { return J{{"start", vec(s)}, {"end", vec(e)}}; }

// ---- primitive cases ----------------------------------------------------------------------------

/// How a primitive case's shapes are drawn.
enum class Mode { General, Grid, Coplanar, Touching, Degenerate };

const std::vector<std::string_view> kPrimitiveOps = {"closest_point_triangle", "triangle_sphere", "triangle_aabb",
                                                     "triangle_obb",           "triangle_plane",  "triangle_triangle",
                                                     "ray_triangle",           "segment_triangle"};

Tri gridTriangle(Rng& rng, int r) {
  for (;;) {
    Tri t{rng.gridPoint(r), rng.gridPoint(r), rng.gridPoint(r)};
    if (!isZero(t.normal())) return t;
  }
}
Tri degenerateTriangle(Rng& rng) {
  const V a = rng.gridPoint(3);
  const V d = rng.gridPoint(2);
  switch (rng.integer(0, 3)) {
    case 0: return {a, add(a, d), add(a, mul(d, rng.integer(-2, 3)))};  // collinear
    case 1: return {a, a, add(a, d)};                                   // repeated corner
    case 2: return {a, add(a, d), a};
    default: return {a, a, a};  // a point
  }
}

/// x moved 1-4 float ulps up or down (a float again).
double nudgedFloat(double x, Rng& rng) {
  float f = float(x);
  const int steps = rng.integer(1, 4);
  const float toward = rng.chance(0.5) ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
  for (int i = 0; i < steps; ++i) f = std::nextafter(f, toward);
  return double(f);
}

/// A sliver triangle (height far below its longest edge, rarely exactly degenerate), float
/// corners in a random order: a needle whose tiny edge lies near the origin (10^-8 to 10^-25)
/// against a corner ~1 away, a needle whose tiny edge is a few float ulps long at a corner ~1
/// from the origin, or a flat cap (the midpoint of two corners moved a few ulps). RTCD's region
/// tests cancel on such triangles (found by crux diff: closest points off the triangle, a sphere contact
/// 6 % too deep, capsules rejected by the tilted plane).
Tri sliverTriangle(Rng& rng) {
  Tri t;
  switch (rng.integer(0, 2)) {
    case 0: {
      const double s = std::pow(10.0, -rng.uniform(8, 25));
      t = {toFloat(rng.floatPoint(s)), toFloat(rng.floatPoint(s)), toFloat(rng.floatPoint(1))};
      break;
    }
    case 1: {
      const V a = toFloat(rng.floatPoint(1));
      V b = a;
      for (double& x : b) x = nudgedFloat(x, rng);
      t = {a, b, toFloat(rng.floatPoint(1))};
      break;
    }
    default: {
      const V a = toFloat(rng.floatPoint(1)), b = toFloat(rng.floatPoint(1));
      V m = toFloat(mul(add(a, b), 0.5));
      double& x = m[std::size_t(rng.integer(0, 2))];
      x = nudgedFloat(x, rng);
      t = {a, b, m};
    }
  }
  switch (rng.integer(0, 2)) {
    case 0: return t;
    case 1: return {t.b, t.c, t.a};
    default: return {t.c, t.a, t.b};
  }
}

/// A point of triangle t with integer coordinates when t's are multiples of 6: a corner, an
/// edge midpoint or the centroid.
V pointOn(const Tri& t, Rng& rng) {
  switch (rng.integer(0, 4)) {
    case 0: return t.a;
    case 1: return t.b;
    case 2: return mul(add(t.a, t.b), 0.5);
    case 3: {
      // the centroid when it is on the grid (coordinates that are multiples of 3), else a corner
      const V sum = add(add(t.a, t.b), t.c);
      const V centroid = mul(sum, 1.0 / 3.0);
      for (std::size_t i = 0; i < 3; ++i)
        if (std::fmod(sum[i], 3.0) != 0) return t.c;
      return centroid;
    }
    default: return mul(add(t.b, t.c), 0.5);
  }
}

/// The corner of t extreme along +axis (sign 1) or -axis (sign -1), and its coordinate.
V extremeCorner(const Tri& t, int axis, int sign) {
  V best = t.a;
  for (const V& p : {t.b, t.c})
    if (sign * p[std::size_t(axis)] > sign * best[std::size_t(axis)]) best = p;
  return best;
}

struct Shapes {
  J query = J::object();
  bool grid = true;
};

/// Fills the op's shape fields of `q` for triangle t (the triangle field itself is set by the
/// caller).
void primitiveShape(std::string_view op, const Tri& t, Mode mode, Rng& rng, J& q) {
  const bool general = mode == Mode::General;
  auto point = [&](double r) { return general ? toFloat(rng.floatPoint(r)) : rng.gridPoint(int(r) + 1); };
  const int axis = rng.integer(0, 2);
  const int sign = rng.chance(0.5) ? 1 : -1;
  V unitAxis = {0, 0, 0};
  unitAxis[std::size_t(axis)] = sign;
  // the coplanar mode puts everything in the plane of t (t lies in a coordinate plane there)
  const int flatAxis = t.normal()[0] != 0 ? 0 : t.normal()[1] != 0 ? 1 : 2;
  auto flatten = [&](V p) {
    if (mode == Mode::Coplanar) p[std::size_t(flatAxis)] = t.a[std::size_t(flatAxis)];
    return p;
  };

  if (op == "closest_point_triangle") {
    V p = point(4);
    if (mode == Mode::Touching) p = add(pointOn(t, rng), mul(t.normal(), rng.integer(-1, 1)));
    q["point"] = vec(flatten(p));
  } else if (op == "triangle_sphere") {
    if (mode == Mode::Touching) {
      const double r = rng.integer(0, 3);
      q["sphere"] = sphereJson(add(extremeCorner(t, axis, sign), mul(unitAxis, r)), r);
    } else {
      q["sphere"] = sphereJson(flatten(point(3)), general ? toFloat(rng.uniform(0, 1)) : rng.integer(0, 3));
    }
  } else if (op == "triangle_aabb" || op == "triangle_obb") {
    V lo, hi;
    if (mode == Mode::Touching) {
      // a box on the far side of the plane through t's extreme corner, covering that corner's
      // other coordinates: touches at a corner, an edge or a face
      const V c = extremeCorner(t, axis, sign);
      for (std::size_t i = 0; i < 3; ++i) {
        lo[i] = c[i] - rng.integer(0, 2);
        hi[i] = c[i] + rng.integer(0, 2);
      }
      const auto a = std::size_t(axis);
      if (sign > 0) {
        lo[a] = c[a];
        hi[a] = c[a] + rng.integer(0, 2);
      } else {
        hi[a] = c[a];
        lo[a] = c[a] - rng.integer(0, 2);
      }
    } else {
      lo = flatten(point(3));
      const V ext = general ? V{toFloat(rng.uniform(0, 1)), toFloat(rng.uniform(0, 1)), toFloat(rng.uniform(0, 1))}
                            : V{double(rng.integer(0, 3)), double(rng.integer(0, 3)), double(rng.integer(0, 3))};
      hi = add(lo, ext);
      if (mode == Mode::Coplanar && rng.chance(0.5)) hi[std::size_t(flatAxis)] = lo[std::size_t(flatAxis)];
      if (general) hi = toFloat(hi);
    }
    if (op == "triangle_aabb") {
      q["aabb"] = aabbJson(lo, hi);
    } else {
      const V center = mul(add(lo, hi), 0.5);
      const V ext = mul(sub(hi, lo), 0.5);
      std::array<V, 3> axes;
      V half;
      if (general) {
        axes = rotationMatrix(randomRotation(rng));
        half = ext;
      } else {
        axes = gridFrame(rng);
        // the box keeps its extent along each world axis: half[i] is the extent along axes[i]
        for (std::size_t i = 0; i < 3; ++i)
          for (std::size_t k = 0; k < 3; ++k)
            if (axes[i][k] != 0) half[i] = ext[k];
      }
      q["obb"] = obbJson(toFloat(center), toFloat(half), axes);
    }
  } else if (op == "triangle_plane") {
    V n = general ? toFloat(rng.floatPoint(1)) : rng.nonZeroGrid(2);
    if (isZero(n)) n = {0, 0, 1};
    double d = general ? toFloat(rng.uniform(-1, 1)) : rng.integer(-4, 4);
    if (mode == Mode::Touching) {
      d = std::max({dot(n, t.a), dot(n, t.b), dot(n, t.c)});
      if (sign < 0) d = std::min({dot(n, t.a), dot(n, t.b), dot(n, t.c)});
    } else if (mode == Mode::Coplanar) {
      n = {0, 0, 0};
      n[std::size_t(flatAxis)] = rng.integer(1, 3) * sign;
      d = n[std::size_t(flatAxis)] * t.a[std::size_t(flatAxis)];
    }
    q["plane"] = planeJson(n, d);
  } else if (op == "triangle_triangle") {
    Tri b;
    if (mode == Mode::Touching) {
      // b has a corner on t and its other corners on one side of t's plane
      const V x = pointOn(t, rng);
      const V n = t.normal();
      const int side = rng.chance(0.5) ? 1 : -1;
      V u, w;
      do {
        u = rng.gridPoint(3);
        w = rng.gridPoint(3);
      } while (side * dot(n, u) < 0 || side * dot(n, w) < 0 || isZero(cross(u, w)));
      b = {x, add(x, u), add(x, w)};
    } else if (mode == Mode::General) {
      b = {toFloat(rng.floatPoint(1)), toFloat(rng.floatPoint(1)), toFloat(rng.floatPoint(1))};
    } else {
      b = gridTriangle(rng, 4);
      b = {flatten(b.a), flatten(b.b), flatten(b.c)};
    }
    q["b"] = triJson(b);
  } else if (op == "ray_triangle" || op == "segment_triangle") {
    V o = flatten(point(5));
    V target = mode == Mode::Touching || rng.chance(0.3) ? pointOn(t, rng) : flatten(point(3));
    if (general && rng.chance(0.5)) target = toFloat(pointOn(t, rng));
    V d = sub(target, o);
    if (isZero(d)) d = {0, 0, 1};
    if (op == "ray_triangle") {
      if (!general && mode != Mode::Touching && rng.chance(0.3)) d = rng.nonZeroGrid(2);
      q["ray"] = rayJson(o, toFloat(d));
    } else {
      V e = target;
      if (rng.chance(0.4)) e = add(target, d);  // passes through the target
      q["segment"] = segmentJson(o, toFloat(e));
    }
  }
}

/// Multiplies every coordinate-like number of a query (points, radii, extents, offsets) by s.
void scaleShapes(J& j, double s, const std::string& key = "") {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string& k = it.key();
      if (k == "dir" || k == "normal" || k == "axes" || k == "rotation" || k == "triangles" || k == "op" ||
          k == "id" || k == "name" || k == "mesh" || k == "path" || k == "model")
        continue;
      scaleShapes(*it, s, k);
    }
  } else if (j.is_array()) {
    for (auto& e : j) scaleShapes(e, s, key);
  } else if (j.is_number()) {
    j = num(toFloat(j.get<double>() * s));
  }
}

/// Applies a rigid motion to a primitive query: points and directions rotate, boxes translate
/// only, planes move with the motion.
void transformShapes(J& q, const std::array<V, 3>& m, V t) {
  auto point = [&](J& p) {
    const V v = {p[0].get<double>(), p[1].get<double>(), p[2].get<double>()};
    p = vec(toFloat(add(apply(m, v), t)));
  };
  auto direction = [&](J& p) {
    const V v = {p[0].get<double>(), p[1].get<double>(), p[2].get<double>()};
    p = vec(toFloat(apply(m, v)));
  };
  for (const char* key : {"triangle", "a", "b"})
    if (q.contains(key) && q[key].is_array())
      for (auto& p : q[key]) point(p);
  if (q.contains("point")) point(q["point"]);
  if (q.contains("sphere")) point(q["sphere"]["center"]);
  if (q.contains("aabb")) {
    for (const char* k : {"min", "max"}) {
      J& p = q["aabb"][k];
      p = vec(toFloat(add({p[0].get<double>(), p[1].get<double>(), p[2].get<double>()}, t)));
    }
  }
  if (q.contains("obb")) {
    point(q["obb"]["center"]);
    // axes stay in double: float-rounded frames are not orthonormal to double precision
    for (auto& a : q["obb"]["axes"]) a = vec(apply(m, {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()}));
  }
  if (q.contains("plane")) {
    J& n = q["plane"]["normal"];
    direction(n);
    const V nn = {n[0].get<double>(), n[1].get<double>(), n[2].get<double>()};
    q["plane"]["d"] = num(toFloat(q["plane"]["d"].get<double>() + dot(nn, t)));
  }
  if (q.contains("ray")) {
    point(q["ray"]["origin"]);
    direction(q["ray"]["dir"]);
  }
  if (q.contains("segment")) {
    point(q["segment"]["start"]);
    point(q["segment"]["end"]);
  }
}

/// Moves one coordinate of one point of the query a few float ulps (nudgedFloat).
void nudge(J& q, Rng& rng) {
  std::vector<J*> coords;
  std::function<void(J&, const std::string&)> collect = [&](J& j, const std::string& key) {
    if (key == "dir" || key == "normal" || key == "axes" || key == "half" || key == "radius") return;
    if (j.is_object()) {
      for (auto it = j.begin(); it != j.end(); ++it) collect(*it, it.key());
    } else if (j.is_array()) {
      for (auto& e : j) collect(e, key);
    } else if (j.is_number() && key != "op") {
      coords.push_back(&j);
    }
  };
  collect(q, "");
  if (coords.empty()) return;
  J& c = *coords[rng.next() % coords.size()];
  c = num(nudgedFloat(c.get<double>(), rng));
}

J request(std::string_view op) { return J{{"op", std::string(op)}}; }

/// A primitive case of one of the primitive families.
DiffCase primitiveCase(std::string_view family, std::string_view op, Rng& rng) {
  DiffCase c;
  Mode mode = Mode::Grid;
  bool grid = true;
  if (family == "general") {
    mode = Mode::General;
    grid = false;
  } else if (family == "coplanar") {
    mode = Mode::Coplanar;
  } else if (family == "touching") {
    mode = Mode::Touching;
  } else if (family == "degenerate") {
    mode = Mode::Degenerate;
  } else if (family == "sliver") {
    mode = Mode::General;
    grid = false;
  } else if (family != "grid") {
    // near_degenerate, huge, tiny, transformed: a grid-built case, then modified
    const std::array<Mode, 4> bases = {Mode::Touching, Mode::Coplanar, Mode::Grid, Mode::General};
    mode = bases[std::size_t(rng.integer(0, family == "near_degenerate" ? 1 : 3))];
    grid = false;
  }
  Tri t;
  if (family == "sliver") {
    t = sliverTriangle(rng);
  } else if (mode == Mode::General) {
    t = {toFloat(rng.floatPoint(1)), toFloat(rng.floatPoint(1)), toFloat(rng.floatPoint(1))};
  } else if (mode == Mode::Degenerate) {
    t = degenerateTriangle(rng);
  } else if (mode == Mode::Coplanar) {
    t = gridTriangle(rng, 4);
    const int flat = rng.integer(0, 2);
    const double level = rng.integer(-3, 3);
    for (V* p : {&t.a, &t.b, &t.c}) (*p)[std::size_t(flat)] = level;
    if (isZero(t.normal())) t = {V{0, 0, level}, V{4, 0, level}, V{0, 4, level}};
    if (flat != 2 && t.normal()[std::size_t(flat)] == 0) t = {V{level, 0, 0}, V{level, 4, 0}, V{level, 0, 4}};
  } else {
    t = gridTriangle(rng, 3);
    if (mode == Mode::Touching) t = {mul(t.a, 6), mul(t.b, 6), mul(t.c, 6)};  // edge midpoints, centroid on the grid
  }
  J q = request(op);
  q["triangle"] = triJson(t);
  primitiveShape(op, t, mode, rng, q);
  if (op == "triangle_triangle") {  // the protocol names its operands a and b
    J renamed = request(op);
    renamed["a"] = q["triangle"];
    renamed["b"] = q["b"];
    q = renamed;
  }
  c.featureSize = mode == Mode::General ? 0.5 : 1;
  if (family == "near_degenerate") {
    nudge(q, rng);
    if (q.contains("aabb")) {  // a nudged corner may cross the other one: keep min <= max
      for (std::size_t i = 0; i < 3; ++i) {
        J& lo = q["aabb"]["min"][i];
        J& hi = q["aabb"]["max"][i];
        if (lo.get<double>() > hi.get<double>()) std::swap(lo, hi);
      }
    }
  } else if (family == "huge" || family == "tiny") {
    const double s = family == "huge" ? 1e6 : 1e-6;
    scaleShapes(q, s);
    c.featureSize *= s;
  } else if (family == "transformed") {
    const auto rot = rotationMatrix(randomRotation(rng));
    transformShapes(q, rot, toFloat(rng.floatPoint(5)));
  }
  c.exactGrid = grid;
  c.query = q.dump();
  return c;
}

// ---- meshes -------------------------------------------------------------------------------------

/// A mesh as protocol arrays.
struct MeshData {
  std::vector<V> vertices;
  std::vector<std::array<int, 3>> triangles;
  Tri triangle(std::size_t i) const {
    const auto& t = triangles[i];
    return {vertices[std::size_t(t[0])], vertices[std::size_t(t[1])], vertices[std::size_t(t[2])]};
  }
};

J meshLine(const std::string& name, const MeshData& m) {
  J vs = J::array(), ts = J::array();
  for (const V& v : m.vertices) vs.push_back(vec(v));
  for (const auto& t : m.triangles) ts.push_back(J::array({t[0], t[1], t[2]}));
  J line = request("mesh");
  line["name"] = name;
  line["vertices"] = vs;
  line["triangles"] = ts;
  return line;
}

/// A closed axis-aligned box mesh (12 triangles) with integer corners lo, lo + size.
MeshData boxMesh(V lo, V size) {
  MeshData m;
  for (int i = 0; i < 8; ++i)
    m.vertices.push_back({lo[0] + (i & 1 ? size[0] : 0), lo[1] + (i & 2 ? size[1] : 0), lo[2] + (i & 4 ? size[2] : 0)});
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

/// A soup of grid triangles (some touching, coplanar or degenerate).
MeshData gridSoup(Rng& rng, int count, int r) {
  MeshData m;
  for (int i = 0; i < count; ++i) {
    const Tri t = rng.chance(0.1) ? degenerateTriangle(rng) : gridTriangle(rng, r);
    const int base = int(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {t.a, t.b, t.c});
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

MeshData generalSoup(Rng& rng, int count) {
  MeshData m;
  for (int i = 0; i < count; ++i) {
    const V center = rng.floatPoint(2);
    const int base = int(m.vertices.size());
    for (int k = 0; k < 3; ++k) m.vertices.push_back(toFloat(add(center, rng.floatPoint(0.7))));
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

MeshData smallMesh(Rng& rng, bool general) {
  if (general) return generalSoup(rng, rng.integer(4, 12));
  if (rng.chance(0.5)) {
    return boxMesh(rng.gridPoint(2), {double(rng.integer(1, 3)), double(rng.integer(1, 3)), double(rng.integer(1, 3))});
  }
  return gridSoup(rng, rng.integer(4, 12), 4);
}

const std::vector<std::pair<std::string_view, std::string_view>> kMeshQueryOps = {
    {"mesh_ray", "ray_triangle"},          {"mesh_segment", "segment_triangle"}, {"mesh_sphere", "triangle_sphere"},
    {"mesh_aabb", "triangle_aabb"},        {"mesh_obb", "triangle_obb"},         {"mesh_plane", "triangle_plane"},
    {"mesh_triangle", "triangle_triangle"}};

std::string_view primitiveOf(std::string_view meshOp) {
  std::string_view base = meshOp.substr(meshOp.find('_') + 1);
  for (const auto& [m, p] : kMeshQueryOps)
    if (m.substr(m.find('_') + 1) == base) return p;
  return {};
}

/// Copies the shape fields of a primitive query onto a mesh/model/scene query (the primitive's
/// "b" triangle becomes the query's "triangle").
void copyShape(const J& from, J& to) {
  for (auto it = from.begin(); it != from.end(); ++it) {
    if (it.key() == "op") continue;
    to[it.key() == "b" ? "triangle" : it.key()] = *it;
  }
}

/// A query shape near triangle t of a mesh, for a mesh/model query op.
J shapeNear(std::string_view op, const Tri& t, bool general, Rng& rng) {
  J prim = J::object();
  Mode mode = general ? Mode::General : (rng.chance(0.6) ? Mode::Touching : Mode::Grid);
  Tri tt = t;
  if (general) {
    // general position around the triangle: offsets from its corners
    primitiveShape(primitiveOf(op), tt, Mode::General, rng, prim);
    const V shift = toFloat(mul(add(add(t.a, t.b), t.c), 1.0 / 3.0));
    transformShapes(prim, {V{1, 0, 0}, V{0, 1, 0}, V{0, 0, 1}}, shift);
  } else {
    primitiveShape(primitiveOf(op), tt, mode, rng, prim);
  }
  return prim;
}

std::string realMeshPath(const DiffGenerator& g, std::string_view name) { return g.meshDir + "/" + std::string(name) + ".off"; }

const Mesh* realMesh(DiffGenerator& g, const std::string& name) {
  if (g.meshDir.empty()) return nullptr;
  auto it = g.realMeshes.find(name);
  if (it == g.realMeshes.end()) {
    std::shared_ptr<const Mesh> mesh;
    try {
      mesh = std::make_shared<const Mesh>(loadMesh(realMeshPath(g, name)));
    } catch (const std::exception&) {
      mesh = nullptr;  // not available: generated meshes only
    }
    it = g.realMeshes.emplace(name, mesh).first;
  }
  return it->second.get();
}

const std::vector<std::string> kRealMeshes = {"bunny00", "cow", "blob-closed", "sphere"};

V toV(const Vec3& v) { return {double(v.x()), double(v.y()), double(v.z())}; }

/// A query near the surface of a real mesh: shapes sized relative to the mesh, placed around
/// one of its vertices (so they touch it sometimes) in general position.
J realMeshQuery(std::string_view op, const Mesh& mesh, Rng& rng, double& featureSize) {
  const Aabb& b = mesh.bounds();
  const V lo = toV(b.min), hi = toV(b.max);
  const double size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const auto& tri = mesh.triangles()[rng.next() % mesh.triangleCount()];
  const Tri t{toV(mesh.vertices()[tri[0]]), toV(mesh.vertices()[tri[1]]), toV(mesh.vertices()[tri[2]])};
  const V anchor = t.a;
  const double r = size * rng.uniform(0.002, 0.1);
  featureSize = r;
  auto around = [&](double spread) { return toFloat(add(anchor, mul(rng.floatPoint(1), spread))); };
  J q = J::object();
  if (op == "mesh_ray" || op == "mesh_segment") {
    const V from = around(size);
    V to = rng.chance(0.5) ? anchor : around(r);
    if (op == "mesh_ray") {
      V d = sub(to, from);
      if (isZero(d)) d = {0, 0, 1};
      q["ray"] = rayJson(from, toFloat(d));
      if (rng.chance(0.3)) q["max"] = num(toFloat(size * rng.uniform(0.1, 1)));
    } else {
      q["segment"] = segmentJson(from, toFloat(to));
    }
  } else if (op == "mesh_sphere") {
    q["sphere"] = sphereJson(around(r), toFloat(r));
  } else if (op == "mesh_aabb") {
    const V c = around(r);
    q["aabb"] = aabbJson(toFloat(sub(c, mul({1, 1, 1}, r))), toFloat(add(c, {r, r * 0.5, r * 2})));
  } else if (op == "mesh_obb") {
    auto axes = rotationMatrix(randomRotation(rng));
    q["obb"] = obbJson(around(r), toFloat({r, r * 0.5, r * 1.5}), axes);
  } else if (op == "mesh_plane") {
    const V n = toFloat(rng.floatPoint(1));
    q["plane"] = planeJson(n, toFloat(dot(n, around(size * 0.3))));
  } else if (op == "mesh_triangle") {
    q["triangle"] = triJson({around(r), around(r), around(r)});
  }
  return q;
}

/// A case of the mesh family: a real mesh (loaded once per run) or small generated meshes.
DiffCase meshCase(std::string_view op, Rng& rng, DiffGenerator& g) {
  DiffCase c;
  const std::string& realName = kRealMeshes[rng.next() % kRealMeshes.size()];
  const Mesh* real = rng.chance(0.35) ? realMesh(g, realName) : nullptr;
  if (op == "mesh_mesh") {
    // two small meshes, placed by transforms (grid: exact rotations; else random)
    const bool general = rng.chance(0.35);
    const MeshData a = smallMesh(rng, general);
    MeshData b = smallMesh(rng, general);
    J ta = J::object(), tb = J::object();
    bool grid = !general;
    if (!general && rng.chance(0.5)) {
      // b gets a triangle touching one of a's triangles, the rest of b far away
      const Tri at = a.triangle(rng.next() % a.triangles.size());
      if (!isZero(at.normal())) {
        J prim = J::object();
        const Tri scaled = at;  // corners on the grid; pointOn may be half-integer: still exact in float
        primitiveShape("triangle_triangle", scaled, Mode::Touching, rng, prim);
        const J& bt = prim["b"];
        const int base = int(b.vertices.size());
        for (auto& v : b.vertices) v = add(v, {40, 0, 0});
        for (const auto& p : bt) b.vertices.push_back({p[0].get<double>(), p[1].get<double>(), p[2].get<double>()});
        b.triangles.push_back({base, base + 1, base + 2});
      }
    }
    if (general) {
      ta["rotation"] = rotationJson(randomRotation(rng));
      ta["translation"] = vec(toFloat(rng.floatPoint(1)));
      tb["rotation"] = rotationJson(randomRotation(rng));
      tb["translation"] = vec(toFloat(rng.floatPoint(1)));
    } else if (rng.chance(0.5)) {
      // the same grid motion for both: contacts stay exact
      const auto& rot = gridRotations()[rng.next() % gridRotations().size()];
      const V t = rng.gridPoint(5);
      for (J* tr : {&ta, &tb}) {
        (*tr)["rotation"] = rotationJson(rot.q);
        (*tr)["translation"] = vec(t);
      }
    }
    if (real && !general && rng.chance(0.5) && real->triangleCount() < 2000) {
      // a small real mesh against a generated one, in general position
      c.setup.push_back(J{{"op", "load_mesh"}, {"name", "real"}, {"path", realMeshPath(g, realName)}}.dump());
      c.sharedSetup = false;
      const Aabb& bb = real->bounds();
      double mag = 0;
      for (int k = 0; k < 3; ++k) mag = std::max({mag, std::fabs(double(bb.min[k])), std::fabs(double(bb.max[k]))});
      c.extraMagnitude = mag;
      c.setup.push_back(meshLine("b", b).dump());
      J q = request(op);
      q["a"] = "real";
      q["b"] = "b";
      tb = J::object();
      tb["translation"] = vec(toFloat(toV(real->vertices()[rng.next() % real->vertexCount()])));
      q["transform_b"] = tb;
      c.query = q.dump();
      c.exactGrid = false;
      return c;
    }
    c.setup.push_back(meshLine("a", a).dump());
    c.setup.push_back(meshLine("b", b).dump());
    J q = request(op);
    q["a"] = "a";
    q["b"] = "b";
    if (!ta.empty()) q["transform_a"] = ta;
    if (!tb.empty()) q["transform_b"] = tb;
    c.query = q.dump();
    c.exactGrid = grid;
    c.featureSize = general ? 0.3 : 1;
    return c;
  }
  J q = request(op);
  q["mesh"] = real ? realName : std::string("m");
  if (real) {
    c.setup.push_back(J{{"op", "load_mesh"}, {"name", realName}, {"path", realMeshPath(g, realName)}}.dump());
    c.sharedSetup = true;
    const Aabb& bb = real->bounds();
    double mag = 0;
    for (int k = 0; k < 3; ++k) mag = std::max({mag, std::fabs(double(bb.min[k])), std::fabs(double(bb.max[k]))});
    c.extraMagnitude = mag;
    double feature = 1;
    copyShape(realMeshQuery(op, *real, rng, feature), q);
    c.featureSize = feature;
    c.exactGrid = false;
  } else {
    const bool general = rng.chance(0.3);
    const MeshData m = smallMesh(rng, general);
    c.setup.push_back(meshLine("m", m).dump());
    Tri t = m.triangle(rng.next() % m.triangles.size());
    copyShape(shapeNear(op, t, general, rng), q);
    if (op == "mesh_ray" && rng.chance(0.2)) q["max"] = num(rng.integer(1, 8));
    c.exactGrid = !general;
    c.featureSize = general ? 0.3 : 1;
  }
  c.query = q.dump();
  return c;
}

// ---- hierarchies and scenes ---------------------------------------------------------------------

/// A model as the generator tracks it: its mesh, parent (-1: none), local motion, and for
/// checking placements the world-space triangles (exact for grid motions).
struct ModelData {
  std::string name;
  int mesh = 0;
  int parent = -1;
  std::array<V, 3> rot;  // rows
  V translation{0, 0, 0};
};

struct World {
  std::vector<MeshData> meshes;
  std::vector<ModelData> models;
  /// World motion of model i: parent ∘ local.
  std::pair<std::array<V, 3>, V> worldMotion(int i) const {
    const ModelData& m = models[std::size_t(i)];
    if (m.parent < 0) return {m.rot, m.translation};
    const auto [pr, pt] = worldMotion(m.parent);
    std::array<V, 3> r{};
    for (std::size_t row = 0; row < 3; ++row)
      for (std::size_t col = 0; col < 3; ++col)
        r[row][col] = pr[row][0] * m.rot[0][col] + pr[row][1] * m.rot[1][col] + pr[row][2] * m.rot[2][col];
    return {r, add(apply(pr, m.translation), pt)};
  }
  Tri worldTriangle(int model, std::size_t tri) const {
    const auto [r, t] = worldMotion(model);
    const Tri local = meshes[std::size_t(models[std::size_t(model)].mesh)].triangle(tri);
    return {add(apply(r, local.a), t), add(apply(r, local.b), t), add(apply(r, local.c), t)};
  }
};

/// Picks a local motion: a grid motion (exact rotation, integer translation) or a random one.
J motion(Rng& rng, bool general, ModelData& m) {
  J tr = J::object();
  if (general) {
    const auto q = randomRotation(rng);
    std::array<double, 4> qf = {toFloat(q[0]), toFloat(q[1]), toFloat(q[2]), toFloat(q[3])};
    m.rot = rotationMatrix(qf);
    m.translation = toFloat(rng.floatPoint(3));
    tr["rotation"] = rotationJson(qf);
  } else {
    const auto& rot = gridRotations()[rng.next() % gridRotations().size()];
    m.rot = rot.m;
    m.translation = rng.gridPoint(3);
    tr["rotation"] = rotationJson(rot.q);
  }
  tr["translation"] = vec(m.translation);
  return tr;
}

/// Sets up meshes and models: a chain (hierarchy family) or several independent models with a
/// few children (scene family). Returns the world as tracked.
World buildModels(Rng& rng, bool general, bool chain, DiffCase& c) {
  World w;
  const int meshCount = rng.integer(1, 2);
  for (int i = 0; i < meshCount; ++i) {
    w.meshes.push_back(smallMesh(rng, general));
    c.setup.push_back(meshLine("m" + std::to_string(i), w.meshes.back()).dump());
  }
  const int count = chain ? rng.integer(2, 4) : rng.integer(3, 6);
  for (int i = 0; i < count; ++i) {
    ModelData m;
    m.name = "n" + std::to_string(i);
    m.mesh = rng.integer(0, meshCount - 1);
    if (chain) {
      m.parent = i - 1;
    } else if (i > 0 && rng.chance(0.25)) {
      m.parent = rng.integer(0, i - 1);
    }
    J line = request("add_model");
    line["name"] = m.name;
    line["mesh"] = "m" + std::to_string(m.mesh);
    line["transform"] = motion(rng, general, m);
    if (!chain && !general) {
      // scene: spread the roots on a grid of spacing 4, so boxes sometimes touch face to face
      if (m.parent < 0) {
        m.translation = {double(4 * rng.integer(-1, 1)), double(4 * rng.integer(-1, 1)), double(rng.integer(-1, 1))};
        line["transform"]["translation"] = vec(m.translation);
      }
    }
    if (m.parent >= 0) line["parent"] = w.models[std::size_t(m.parent)].name;
    w.models.push_back(m);
    c.setup.push_back(line.dump());
  }
  // occasionally move or re-parent a model after the fact (the protocol's mutating ops)
  if (rng.chance(0.3)) {
    const int i = rng.integer(0, count - 1);
    J line = request("set_transform");
    line["model"] = w.models[std::size_t(i)].name;
    line["transform"] = motion(rng, general, w.models[std::size_t(i)]);
    c.setup.push_back(line.dump());
  }
  return w;
}

/// A `model_distance` query between two distinct models of `w` (world space, each placed by its
/// composed parent chain), 20 % with a `max` (an integer on grid cases, so an integer distance
/// exactly at the bound is decided).
J modelDistanceQuery(const World& w, bool general, Rng& rng) {
  J q = request("model_distance");
  const int count = int(w.models.size());
  const int a = rng.integer(0, count - 1);
  const int b = (a + rng.integer(1, count - 1)) % count;
  q["a"] = w.models[std::size_t(a)].name;
  q["b"] = w.models[std::size_t(b)].name;
  if (rng.chance(0.2)) q["max"] = num(general ? toFloat(rng.uniform(0, 2)) : double(rng.integer(0, 3)));
  return q;
}

DiffCase hierarchyCase(std::string_view op, Rng& rng) {
  DiffCase c;
  const bool general = rng.chance(0.3);
  World w = buildModels(rng, general, true, c);
  c.exactGrid = !general;
  c.featureSize = general ? 0.3 : 1;
  if (op == "model_distance") {
    c.query = modelDistanceQuery(w, general, rng).dump();
    return c;
  }
  const int target = rng.integer(0, int(w.models.size()) - 1);
  J q = request(op);
  q["model"] = w.models[std::size_t(target)].name;
  if (op != "children") {
    const MeshData& mesh = w.meshes[std::size_t(w.models[std::size_t(target)].mesh)];
    const Tri t = w.worldTriangle(target, rng.next() % mesh.triangles.size());
    const bool degenerate = isZero(t.normal());
    copyShape(shapeNear("mesh" + std::string(op.substr(op.find('_'))), degenerate ? Tri{t.a, add(t.a, {1, 0, 0}), add(t.a, {0, 1, 0})} : t,
                        general, rng),
              q);
  }
  c.query = q.dump();
  return c;
}

DiffCase sceneCase(std::string_view op, Rng& rng) {
  DiffCase c;
  const bool general = rng.chance(0.3);
  World w = buildModels(rng, general, false, c);
  c.exactGrid = !general;
  c.featureSize = general ? 0.3 : 1;
  if (op == "model_distance") {
    c.query = modelDistanceQuery(w, general, rng).dump();
    return c;
  }
  J q = request(op);
  if (op != "scene_pairs") {
    const int target = rng.integer(0, int(w.models.size()) - 1);
    const MeshData& mesh = w.meshes[std::size_t(w.models[std::size_t(target)].mesh)];
    Tri t = w.worldTriangle(target, rng.next() % mesh.triangles.size());
    if (isZero(t.normal())) t = {t.a, add(t.a, {1, 0, 0}), add(t.a, {0, 1, 0})};
    if (op == "scene_ray") {
      copyShape(shapeNear("mesh_ray", t, general, rng), q);
      if (rng.chance(0.2)) q["max"] = num(rng.integer(1, 10));
    } else {
      const std::vector<std::string_view> shapes = {"mesh_sphere", "mesh_aabb", "mesh_obb"};
      copyShape(shapeNear(rng.pick(shapes), t, general, rng), q);
      if (rng.chance(0.2)) q["bounds"] = true;
    }
  }
  c.query = q.dump();
  return c;
}

// ---- narrow phase: distance, contacts, mesh_distance (model_distance: above) -------------

/// A convex operand of the narrow-phase ops (docs/batch.md "Operands") around `at`: a sphere,
/// box, capsule, hull (4–8 points) or triangle, on the grid (integer coordinates, signed
/// permutation box frames) or in general position (float coordinates, random box frames).
/// With `degenerate`: a zero-radius sphere, a flat box, a capsule with a = b, a hull of
/// collinear or coplanar points, a collinear / point triangle (grid only).
J convexOperand(Rng& rng, bool general, V at, bool degenerate = false) {
  const auto point = [&](int spread) {
    return general ? toFloat(add(at, rng.floatPoint(spread))) : add(at, rng.gridPoint(spread));
  };
  const auto length = [&](int hi) { return general ? toFloat(rng.uniform(0.1, hi)) : double(rng.integer(1, hi)); };
  J o = J::object();
  switch (rng.integer(0, 4)) {
    case 0:
      o["sphere"] = sphereJson(point(1), degenerate ? 0.0 : length(2));
      break;
    case 1: {
      V half = {length(2), length(2), length(1)};
      if (degenerate) half[std::size_t(rng.integer(0, 2))] = 0;
      o["box"] = obbJson(point(1), half, general ? rotationMatrix(randomRotation(rng)) : gridFrame(rng));
      break;
    }
    case 2: {
      const V a = point(1);
      o["capsule"] = J{{"a", vec(a)}, {"b", vec(degenerate ? a : point(2))}, {"radius", num(length(1))}};
      break;
    }
    case 3: {
      J points = J::array();
      const V base = point(1), d = rng.nonZeroGrid(1);
      const V e = rng.nonZeroGrid(1);
      const int n = rng.integer(4, 8);
      for (int i = 0; i < n; ++i) {
        if (!degenerate) points.push_back(vec(point(2)));
        else if (rng.chance(0.5)) points.push_back(vec(add(base, mul(d, rng.integer(-2, 2)))));  // collinear
        else points.push_back(vec(add(add(base, mul(d, rng.integer(-2, 2))), mul(e, rng.integer(-2, 2)))));  // coplanar
      }
      o["hull"] = J{{"points", points}};
      break;
    }
    default: {
      if (degenerate) {
        const Tri t = degenerateTriangle(rng);
        o["triangle"] = triJson({add(t.a, at), add(t.b, at), add(t.c, at)});
      } else {
        o["triangle"] = triJson({point(2), point(2), point(2)});
      }
    }
  }
  return o;
}

/// A box operand (grid frame, integer centre and half extents) and an operand touching one of
/// its faces exactly from outside: a sphere, a box face to face, or a capsule lying on it.
std::pair<J, J> touchingOperands(Rng& rng) {
  const V c = rng.gridPoint(2);
  const V h = {double(rng.integer(1, 2)), double(rng.integer(1, 2)), double(rng.integer(1, 2))};
  const std::array<V, 3> identity = {V{1, 0, 0}, V{0, 1, 0}, V{0, 0, 1}};
  J a = J{{"box", obbJson(c, h, identity)}};
  const std::size_t axis = std::size_t(rng.integer(0, 2));
  const double side = rng.chance(0.5) ? 1 : -1;
  V onFace = c;  // a point of the face (corner, edge or interior, integer)
  for (std::size_t i = 0; i < 3; ++i)
    onFace[i] += i == axis ? side * h[i] : double(rng.integer(-int(h[i]), int(h[i])));
  const double r = double(rng.integer(1, 2));
  V out = {0, 0, 0};
  out[axis] = side;
  J b;
  switch (rng.integer(0, 2)) {
    case 0: b = J{{"sphere", sphereJson(add(onFace, mul(out, r)), r)}}; break;
    case 1: {
      const V hb = {double(rng.integer(1, 2)), double(rng.integer(1, 2)), double(rng.integer(1, 2))};
      b = J{{"box", obbJson(add(onFace, mul(out, hb[axis])), hb, identity)}};
      break;
    }
    default: {
      V along = {0, 0, 0};
      along[(axis + 1) % 3] = double(rng.integer(1, 3));
      const V a0 = add(onFace, mul(out, r));
      b = J{{"capsule", J{{"a", vec(a0)}, {"b", vec(add(a0, along))}, {"radius", num(r)}}}};
    }
  }
  if (rng.chance(0.5)) std::swap(a, b);
  return {a, b};
}

/// A placement of an operand: a grid motion (exact rotation, integer translation) or a random one.
J placement(Rng& rng, bool general) {
  if (general) return J{{"rotation", rotationJson(randomRotation(rng))}, {"translation", vec(toFloat(rng.floatPoint(1)))}};
  const auto& rot = gridRotations()[rng.next() % gridRotations().size()];
  return J{{"rotation", rotationJson(rot.q)}, {"translation", vec(rng.gridPoint(2))}};
}

/// A `distance` or `contacts` case between two convex operands, in one of the primitive families
/// (general, grid, touching, degenerate, near_degenerate, huge, tiny, transformed).
DiffCase narrowConvexCase(std::string_view family, std::string_view op, Rng& rng) {
  DiffCase c;
  const bool general = family == "general" || family == "transformed" || family == "sliver";
  J q = request(op);
  if (family == "touching" || family == "near_degenerate") {
    const auto [a, b] = touchingOperands(rng);
    q["a"] = a;
    q["b"] = b;
  } else if (family == "sliver") {  // a sliver triangle against a general operand near it
    q["a"] = J{{"triangle", triJson(sliverTriangle(rng))}};
    q["b"] = convexOperand(rng, true, toFloat(rng.floatPoint(1)), false);
    if (rng.chance(0.5)) std::swap(q["a"], q["b"]);
  } else {
    q["a"] = convexOperand(rng, general, {0, 0, 0}, family == "degenerate" && rng.chance(0.5));
    const V offset = general ? toFloat(rng.floatPoint(2.5)) : rng.gridPoint(3);
    q["b"] = convexOperand(rng, general, offset, family == "degenerate" && rng.chance(0.5));
    if (family != "transformed" && rng.chance(0.3)) q["b"]["transform"] = placement(rng, general);
  }
  if (op == "contacts" && rng.chance(0.3)) q["margin"] = num(general ? toFloat(rng.uniform(0, 0.5)) : 1);
  c.exactGrid = !general;
  c.featureSize = general ? 0.2 : 1;
  if (family == "near_degenerate") {
    nudge(q, rng);
    c.exactGrid = false;
  } else if (family == "huge" || family == "tiny") {
    const double s = family == "huge" ? 1e6 : 1e-6;
    scaleShapes(q, s);
    c.featureSize *= s;
    c.exactGrid = false;
  } else if (family == "transformed") {
    // one random rigid motion for both operands: the answer's distance and depth are invariant
    const J motion = placement(rng, true);
    q["a"]["transform"] = motion;
    q["b"]["transform"] = motion;
  }
  c.query = q.dump();
  return c;
}

/// Real meshes the narrow-phase ops use: the small ones, and (kLargeRealMeshChance of the
/// picks) the large ones, whose exact answers cost ~40 ms a case (oracle/README.md).
const std::vector<std::string> kNarrowRealMeshes = {"blob-closed", "sphere"};
const std::vector<std::string> kNarrowLargeRealMeshes = {"bunny00", "cow"};
constexpr double kLargeRealMeshChance = 0.05;

/// The chance that a `mesh_distance` case of the mesh family is between two real meshes (the
/// exact backend's tree search makes them cheap: ~40 ms for bunny00 against cow).
constexpr double kRealMeshPairChance = 0.35;

/// Unit quaternion (w, x, y, z) turning unit vector w onto unit vector u, then spinning by
/// `spin` radians about u.
std::array<double, 4> turnOnto(V w, V u, double spin) {
  const V c = cross(w, u);
  double q[4] = {1 + dot(w, u), c[0], c[1], c[2]};
  if (q[0] < 1e-9) {  // opposite: a half turn about any axis normal to w
    const V a = std::fabs(w[0]) < 0.9 ? V{1, 0, 0} : V{0, 1, 0};
    const V n = cross(w, a);
    q[0] = 0;
    q[1] = n[0];
    q[2] = n[1];
    q[3] = n[2];
  }
  const double l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& x : q) x /= l;
  const double h = 0.5 * spin, sw = std::cos(h), s = std::sin(h);
  const double p[4] = {sw, s * u[0], s * u[1], s * u[2]};  // spin ∘ turn (Hamilton product p·q)
  return {p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3], p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2],
          p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1], p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0]};
}

/// `mesh_distance` between two real meshes (kNarrowRealMeshes, or kNarrowLargeRealMeshes with
/// kLargeRealMeshChance each): a randomly turned; b turned so that it lies beyond one of its
/// vertices, that vertex placed near one of a's along a's outward direction there (from a's box
/// centre), at -2 % to +10 % of the smaller mesh's size: apart by a little, touching near a point or
/// crossing. False (nothing written) when a mesh is not available.
bool realMeshPair(Rng& rng, DiffGenerator& g, J& q, DiffCase& c) {
  auto pick = [&]() -> const std::string& {
    const std::vector<std::string>& names = rng.chance(kLargeRealMeshChance) ? kNarrowLargeRealMeshes : kNarrowRealMeshes;
    return names[rng.next() % names.size()];
  };
  const std::string na = pick(), nb = pick();
  const Mesh* ma = realMesh(g, na);
  const Mesh* mb = realMesh(g, nb);
  if (!ma || !mb) return false;
  auto centreSize = [](const Mesh& m, V& centre, double& size, double& mag) {
    const Aabb& bb = m.bounds();
    size = mag = 0;
    for (int k = 0; k < 3; ++k) {
      centre[std::size_t(k)] = 0.5 * (double(bb.min[k]) + double(bb.max[k]));
      size = std::max(size, double(bb.max[k] - bb.min[k]));
      mag = std::max({mag, std::fabs(double(bb.min[k])), std::fabs(double(bb.max[k]))});
    }
  };
  V ca{}, cb{};
  double sa = 0, sb = 0, magA = 0, magB = 0;
  centreSize(*ma, ca, sa, magA);
  centreSize(*mb, cb, sb, magB);
  auto unit = [](V v) {
    const double l = std::sqrt(dot(v, v));
    return l > 0 ? V{v[0] / l, v[1] / l, v[2] / l} : V{0, 0, 1};
  };
  const auto ra = randomRotation(rng);
  const auto Ra = rotationMatrix(ra);
  const V va = apply(Ra, toV(ma->vertices()[rng.next() % ma->vertexCount()]));
  const V outward = unit(sub(va, apply(Ra, ca)));
  const V vb = toV(mb->vertices()[rng.next() % mb->vertexCount()]);
  const auto rb = turnOnto(unit(sub(cb, vb)), outward, rng.uniform(0, 2 * M_PI));
  const double gap = std::min(sa, sb) * rng.uniform(-0.02, 0.1);
  const std::array<V, 3> Rb = rotationMatrix(rb);
  const V at = apply(Rb, vb);
  const V tb = toFloat(V{va[0] + gap * outward[0] - at[0], va[1] + gap * outward[1] - at[1], va[2] + gap * outward[2] - at[2]});
  c.setup.push_back(J{{"op", "load_mesh"}, {"name", na}, {"path", realMeshPath(g, na)}}.dump());
  if (nb != na) c.setup.push_back(J{{"op", "load_mesh"}, {"name", nb}, {"path", realMeshPath(g, nb)}}.dump());
  c.sharedSetup = true;
  q["a"] = na;
  q["b"] = nb;
  q["transform_a"] = J{{"rotation", rotationJson(ra)}, {"translation", vec(V{0, 0, 0})}};
  q["transform_b"] = J{{"rotation", rotationJson(rb)}, {"translation", vec(tb)}};
  if (rng.chance(0.2)) q["max"] = num(toFloat(std::min(sa, sb) * rng.uniform(0, 0.1)));
  c.exactGrid = false;
  c.featureSize = 0.05 * std::min(sa, sb);
  c.extraMagnitude = std::max(magA, std::sqrt(dot(tb, tb)) + magB);
  c.query = q.dump();
  return true;
}

/// A narrow-phase case of the mesh family: `distance` / `contacts` between a mesh (small
/// generated, or a small real mesh) and a convex operand near one of its triangles, in either
/// operand order; `mesh_distance` between two small meshes under grid or random motions.
DiffCase narrowMeshCase(std::string_view op, Rng& rng, DiffGenerator& g) {
  DiffCase c;
  J q = request(op);
  if (op == "mesh_distance") {
    if (rng.chance(kRealMeshPairChance) && realMeshPair(rng, g, q, c)) return c;
    const bool general = rng.chance(0.35);
    c.setup.push_back(meshLine("a", smallMesh(rng, general)).dump());
    c.setup.push_back(meshLine("b", smallMesh(rng, general)).dump());
    q["a"] = "a";
    q["b"] = "b";
    if (rng.chance(0.7)) q["transform_a"] = placement(rng, general);
    if (rng.chance(0.7)) q["transform_b"] = placement(rng, general);
    if (rng.chance(0.2)) q["max"] = num(general ? toFloat(rng.uniform(0, 2)) : double(rng.integer(0, 3)));
    c.exactGrid = !general;
    c.featureSize = general ? 0.3 : 1;
    c.query = q.dump();
    return c;
  }
  const bool large = rng.chance(kLargeRealMeshChance);
  const std::vector<std::string>& names = large ? kNarrowLargeRealMeshes : kNarrowRealMeshes;
  const std::string& realName = names[rng.next() % names.size()];
  const Mesh* real = rng.chance(0.35) ? realMesh(g, realName) : nullptr;
  J meshOperand, shape;
  if (real) {
    c.setup.push_back(J{{"op", "load_mesh"}, {"name", realName}, {"path", realMeshPath(g, realName)}}.dump());
    c.sharedSetup = true;
    const Aabb& bb = real->bounds();
    double mag = 0, size = 0;
    for (int k = 0; k < 3; ++k) {
      mag = std::max({mag, std::fabs(double(bb.min[k])), std::fabs(double(bb.max[k]))});
      size = std::max(size, double(bb.max[k] - bb.min[k]));
    }
    c.extraMagnitude = mag;
    meshOperand = J{{"mesh", realName}};
    const V anchor = toV(real->vertices()[rng.next() % real->vertexCount()]);
    // a general operand of unit size around the origin, scaled to 2-10 % of the mesh, moved to the anchor
    J o = convexOperand(rng, true, {0, 0, 0});
    const double s = toFloat(size * rng.uniform(0.02, 0.1));
    scaleShapes(o, s);
    o["transform"] = J{{"translation", vec(toFloat(anchor))}};
    shape = o;
    c.featureSize = s;
    c.exactGrid = false;
  } else {
    const bool general = rng.chance(0.3);
    const MeshData m = smallMesh(rng, general);
    c.setup.push_back(meshLine("m", m).dump());
    meshOperand = J{{"mesh", "m"}};
    const Tri t = m.triangle(rng.next() % m.triangles.size());
    shape = convexOperand(rng, general, general ? t.a : t.a);
    if (rng.chance(0.3)) meshOperand["transform"] = placement(rng, general);
    c.exactGrid = !general;
    c.featureSize = general ? 0.2 : 1;
  }
  const bool meshFirst = rng.chance(0.5);
  q["a"] = meshFirst ? meshOperand : shape;
  q["b"] = meshFirst ? shape : meshOperand;
  if (op == "contacts" && rng.chance(0.3)) q["margin"] = num(c.exactGrid ? 1.0 : toFloat(0.05 * c.featureSize * 4));
  c.query = q.dump();
  return c;
}

/// The kinds of cast case, on the integer grid (exact rational times of impact for polytopes):
/// a shape moved along a box's face plane into the box from the side (grazing: the contact is
/// tangential to the face, or edge on edge), one lying on the face sliding along it (touching at
/// the start: t = 0), one starting in contact or overlapping and moving anywhere, and one cast
/// through a thin or degenerate triangle.
enum class CastKind { Grazing, Sliding, Start, Thin };

/// The moving operand of a cast case: a box, a sphere or a capsule lying along axis `u`, with
/// the half extents of its bounding box; json(centre) places it.
struct CastMover {
  int shape = 0;  ///< 0 box, 1 sphere, 2 capsule
  V half{1, 1, 1};
  double radius = 1, capsuleHalf = 1;
  std::size_t u = 0;

  CastMover(Rng& rng, std::size_t alongU) : shape(rng.integer(0, 2)), u(alongU) {
    if (shape == 0) half = {double(rng.integer(1, 2)), double(rng.integer(1, 2)), double(rng.integer(1, 2))};
    if (shape == 1) radius = double(rng.integer(1, 2)), half = {radius, radius, radius};
    if (shape == 2) capsuleHalf = double(rng.integer(1, 2)), half = {1, 1, 1}, half[u] += capsuleHalf;
  }
  J json(V centre) const {
    const std::array<V, 3> identity = {V{1, 0, 0}, V{0, 1, 0}, V{0, 0, 1}};
    if (shape == 0) return J{{"box", obbJson(centre, half, identity)}};
    if (shape == 1) return J{{"sphere", sphereJson(centre, radius)}};
    V e = {0, 0, 0};
    e[u] = capsuleHalf;
    return J{{"capsule", J{{"a", vec(sub(centre, e))}, {"b", vec(add(centre, e))}, {"radius", num(1)}}}};
  }
};

/// A `cast` case of the cast family (linear motion; see CastKind).
DiffCase castCase(Rng& rng) {
  DiffCase c;
  J q = request("cast");
  const std::array<V, 3> identity = {V{1, 0, 0}, V{0, 1, 0}, V{0, 0, 1}};
  const CastKind kind = CastKind(rng.integer(0, 3));
  const std::size_t axis = std::size_t(rng.integer(0, 2)), u = (axis + 1) % 3, w = (axis + 2) % 3;
  const double side = rng.chance(0.5) ? 1 : -1, lateral = rng.chance(0.5) ? 1 : -1;
  const V bc = rng.gridPoint(2);
  const V bh = {double(rng.integer(1, 3)), double(rng.integer(1, 3)), double(rng.integer(1, 3))};
  const CastMover mover(rng, u);
  V centre = bc, motion = {0, 0, 0};
  if (kind == CastKind::Thin) {
    // a triangle in the plane normal to `axis` through bc, long along u, 1 (or 0: a segment)
    // across w; the mover starts 1..3 clear of the plane and crosses it near the thin part
    const double length = double(rng.integer(4, 12)), height = rng.chance(0.25) ? 0 : 1;
    V t1 = bc, t2 = bc;
    t1[u] += length;
    t2[u] += double(rng.integer(0, int(length)));
    t2[w] += height;
    q["b"] = J{{"triangle", J::array({vec(bc), vec(t1), vec(t2)})}};
    centre[u] += double(rng.integer(-1, int(length) + 1));
    centre[w] += double(rng.integer(-2, 2));
    centre[axis] += side * (mover.half[axis] + double(rng.integer(1, 3)));
    motion[axis] = -2 * (centre[axis] - bc[axis]);
  } else {
    q["b"] = J{{"box", obbJson(bc, bh, identity)}};
    centre[axis] += side * (bh[axis] + mover.half[axis]);  // flush with b's face plane
    if (kind == CastKind::Grazing) {
      // beside the box along u by 1..3, within (or edge on edge at) its extent along w, moving
      // along the face plane into it
      const double gap = double(rng.integer(1, 3));
      centre[u] += lateral * (bh[u] + mover.half[u] + gap);
      centre[w] += rng.chance(0.3) ? lateral * (bh[w] + mover.half[w]) : double(rng.integer(-int(bh[w]), int(bh[w])));
      motion[u] = -lateral * (gap + double(rng.integer(0, 4)));
    } else {
      centre[u] += double(rng.integer(-int(bh[u]), int(bh[u])));
      centre[w] += double(rng.integer(-int(bh[w]), int(bh[w])));
      if (kind == CastKind::Sliding) {  // on the face, moving along it
        motion[u] = double(rng.integer(-4, 4));
        motion[w] = double(rng.integer(-4, 4));
        if (isZero(motion)) motion[u] = 3;
      } else {  // Start: flush or sunk by 1, moving anywhere
        if (rng.chance(0.5)) centre[axis] -= side;
        motion = rng.nonZeroGrid(4);
      }
    }
  }
  q["a"] = mover.json(centre);
  if (rng.chance(0.5)) {  // one grid placement of both (the time of impact does not change)
    const auto& rot = gridRotations()[rng.next() % gridRotations().size()];
    const J pose = J{{"rotation", rotationJson(rot.q)}, {"translation", vec(rng.gridPoint(2))}};
    q["a"]["transform"] = pose;
    q["b"]["transform"] = pose;
    motion = apply(rot.m, motion);
  }
  q["motion"] = vec(motion);
  c.exactGrid = true;
  c.featureSize = 1;
  c.query = q.dump();
  return c;
}

bool isNarrowOp(std::string_view op) {
  return op == "distance" || op == "contacts" || op == "mesh_distance" || op == "model_distance";
}

const std::vector<std::string_view> kMeshOps = {"mesh_ray",      "mesh_segment", "mesh_sphere", "mesh_aabb",
                                                "mesh_obb",      "mesh_plane",   "mesh_triangle", "mesh_mesh",
                                                "distance",      "contacts",     "mesh_distance"};
/// The primitive ops and the convex-pair narrow-phase ops (not in the coplanar family, whose
/// cases are built around one triangle's plane).
const std::vector<std::string_view> kPrimitiveAndNarrowOps = {
    "closest_point_triangle", "triangle_sphere", "triangle_aabb", "triangle_obb", "triangle_plane",
    "triangle_triangle",      "ray_triangle",    "segment_triangle", "distance", "contacts"};
const std::vector<std::string_view> kModelOps = {"model_ray", "model_segment",  "model_sphere", "model_aabb",
                                                 "model_obb", "model_plane",    "model_triangle", "children",
                                                 "model_distance"};
const std::vector<std::string_view> kSceneOps = {"scene_ray", "scene_query", "scene_pairs", "model_distance"};
const std::vector<std::string_view> kCastOps = {"cast"};

}  // namespace

const std::vector<std::string_view>& diffFamilies() {
  static const std::vector<std::string_view> families = {"general", "grid",        "coplanar", "touching",
                                                         "degenerate", "near_degenerate", "sliver", "huge", "tiny",
                                                         "transformed", "mesh",    "hierarchy", "scene", "cast"};
  return families;
}

const std::vector<std::string_view>& diffFamilyOps(std::string_view family) {
  if (family == "mesh") return kMeshOps;
  if (family == "hierarchy") return kModelOps;
  if (family == "scene") return kSceneOps;
  if (family == "coplanar") return kPrimitiveOps;
  if (family == "cast") return kCastOps;
  return kPrimitiveAndNarrowOps;
}

std::uint64_t caseSeed(std::uint64_t seed, std::uint64_t index) {
  Rng a{seed};
  Rng b{a.next() ^ (index * 0xd1342543de82ef95ull)};
  return b.next();
}

std::optional<DiffCase> generateCase(std::string_view family, std::uint64_t seed, std::uint64_t index,
                                     DiffGenerator& generator) {
  const auto& families = diffFamilies();
  if (std::find(families.begin(), families.end(), family) == families.end())
    throw InvalidInput("families: unknown family \"" + std::string(family) + "\"");
  std::vector<std::string_view> ops;
  for (const auto op : diffFamilyOps(family))
    if (generator.ops.empty() || std::find(generator.ops.begin(), generator.ops.end(), op) != generator.ops.end())
      ops.push_back(op);
  if (ops.empty()) return std::nullopt;
  Rng rng{caseSeed(seed, index)};
  const std::string_view op = ops[rng.next() % ops.size()];
  DiffCase c;
  if (family == "cast") {
    c = castCase(rng);
  } else if (family == "hierarchy") {
    c = hierarchyCase(op, rng);
  } else if (family == "scene") {
    c = sceneCase(op, rng);
  } else if (isNarrowOp(op)) {
    c = family == "mesh" ? narrowMeshCase(op, rng, generator) : narrowConvexCase(family, op, rng);
  } else if (family == "mesh") {
    c = meshCase(op, rng, generator);
  } else {
    c = primitiveCase(family, op, rng);
  }
  c.family = std::string(family);
  c.seed = seed;
  c.index = index;
  c.op = std::string(op);
  return c;
}

}  // namespace crux::cli
