/// @file diff.cpp  `crux diff`: running cases on the backends, classifying the answers against
/// the exact arbiter, shrinking, and the run's summary (docs/diff.md).

#include "cli/diff.hpp"

#include <crux/error.hpp>

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

/// Compares answers (neither an error). Booleans and lists exactly (a bounds-only scene query
/// may return a superset: broad phases pad bounds), numbers within `tolerance`.
Difference compareAnswers(std::string_view op, const J& query, const J& got, const J& exact, double tolerance) {
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
  for (const Vec3d& off : probeOffsets(tau, !c.sharedSetup)) {
    const auto moved = translatedCase(c, off);
    if (!moved) return false;
    const Answer p = probeExact(*moved);
    if (hasError(p)) continue;
    if (matchGot) {
      if (compareAnswers(c.op, query, got, p, numTol) == Difference::None) return true;
    } else if (compareAnswers(c.op, query, p, exact, 0) != Difference::None) {
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

// ---- JSON editing helpers ------------------------------------------------------------------------

void moveVec(J& v, const Vec3d& off) {
  for (std::size_t i = 0; i < 3; ++i) v[i] = v[i].get<double>() + off[Eigen::Index(i)];
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

std::optional<DiffCase> translatedCase(const DiffCase& c, const Vec3d& offset) {
  DiffCase out = c;
  J q = J::parse(c.query, nullptr, false);
  if (!q.is_object()) return std::nullopt;
  if (c.op == "mesh_mesh") {
    J& tb = q["transform_b"];
    if (!tb.is_object()) tb = J::object();
    if (!tb.contains("translation")) tb["translation"] = J::array({0, 0, 0});
    moveVec(tb["translation"], offset);
  } else if (c.op == "scene_pairs") {
    // move the last model added
    for (auto line = out.setup.rbegin(); line != out.setup.rend(); ++line) {
      J m = J::parse(*line, nullptr, false);
      if (!m.is_object() || m.value("op", "") != "add_model") continue;
      J& tr = m["transform"];
      if (!tr.is_object()) tr = J::object();
      if (!tr.contains("translation")) tr["translation"] = J::array({0, 0, 0});
      moveVec(tr["translation"], offset);
      *line = m.dump();
      return out;
    }
    return std::nullopt;
  } else {
    const J qt = q.contains("triangle") && c.op == "triangle_triangle" ? J() : J();
    (void)qt;
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

struct DiffRunner::Impl {
  struct Prepared {
    std::unique_ptr<BatchState> state;
    std::optional<Answer> setupError;
  };
  std::map<std::string, Prepared> shared;
  std::map<std::string, WorldTolerance, std::less<>> tolerances;
};

DiffRunner::DiffRunner() : impl_(std::make_unique<Impl>()) {}
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
}  // namespace

Answer DiffRunner::run(const DiffCase& c, std::string_view backend) {
  const auto b = parseBackend(backend);
  if (!b) throw InvalidInput("backends: unknown backend \"" + std::string(backend) + "\"");
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

Classification classifyAnswer(const DiffCase& c, std::string_view backend, const Answer& got, const Answer& exact,
                              const WorldTolerance& tol, const WorldTolerance& exactTol,
                              const std::function<Answer(const DiffCase&)>& probeExact) {
  const std::string exactError = errorText(exact), gotError = errorText(got);
  if (!exactError.empty()) {
    if (!gotError.empty() && !startsWith(exactError, "unsupported:") && !startsWith(gotError, "unsupported:"))
      return {Verdict::Agree, "", "both reject the input"};
    if (startsWith(gotError, "unsupported:")) return {Verdict::Unsupported, "", gotError};
    return {Verdict::NoArbiter, "", exactError};
  }
  if (!gotError.empty()) {
    if (startsWith(gotError, "unsupported:")) return {Verdict::Unsupported, "", gotError};
    return {backend == "native" ? Verdict::CruxWrong : Verdict::Error, "error-answer", gotError};
  }
  const J query = J::parse(c.query, nullptr, false);
  const double s = std::max(caseMagnitude(c), 1e-300);
  const double tau = tol.at(s);
  const double numTol = tau + exactTol.at(s);
  const Difference diff = compareAnswers(c.op, query, got, exact, numTol);
  if (diff == Difference::None) return {Verdict::Agree, "", ""};
  const bool native = backend == "native";
  std::ostringstream detail;
  detail << std::setprecision(17) << backend << " " << got.dump() << " vs exact " << exact.dump();
  if (diff == Difference::Shape) return {native ? Verdict::CruxWrong : Verdict::Error, "answer-shape", detail.str()};
  const bool boolean = diff == Difference::Boolean || diff == Difference::List;
  if (native && c.exactGrid && boolean) return {Verdict::CruxWrong, "grid-exactness", detail.str()};
  if (!native && tol.minFeature > 0 && std::min(c.featureSize, smallestShape(query)) < tol.minFeature)
    return {Verdict::WithinTolerance, "below-min-feature", detail.str()};
  const bool within = probeFlips(c, query, exact, got, tau, numTol, probeExact, true);
  if (native) return {within ? Verdict::WithinTolerance : Verdict::CruxWrong, within ? "boundary" : "beyond-tolerance", detail.str()};

  // a peer: the likely cause, most specific rule first (also recorded for disagreements within
  // tolerance, whose cause is "boundary" when no specific rule applies)
  const auto tris = caseTriangles(c, query);
  const bool bullet = backend == "bullet", fcl = backend == "fcl";
  const Verdict verdict = within ? Verdict::WithinTolerance : Verdict::PeerWrong;
  auto peer = [&](const char* cause) { return Classification{verdict, cause, detail.str()}; };
  if (fcl && c.op == "closest_point_triangle" && query.contains("point") &&
      maxDiff(exact["point"], query["point"]) == 0)
    return peer("nearest-points-in-collision");
  if (bullet && isRayOrSegmentOp(c.op) && endpointOnPlane(query, tris)) return peer("plane-endpoint");
  for (const auto& t : caseTriangles(c, query, true))
    if (degenerate(t)) return peer("degenerate-triangle");
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
  if (diff == Difference::Numeric) {
    // both found a contact; the numbers differ beyond the declared tolerance
    double worst = maxDiff(got["point"], exact["point"]);
    if (got.contains("t")) worst = std::max(worst, std::fabs(got["t"].get<double>() - exact["t"].get<double>()));
    return peer(worst <= 1e-3 * std::max(s, 1.0) ? "precision" : "unexplained");
  }
  if (probeFlips(c, query, exact, got, 1e-3 * s, numTol, probeExact, false)) return peer("touching");
  if (bullet && probeFlips(c, query, exact, got, 0.04, numTol, probeExact, false)) return peer("margin");
  if (bullet && c.op == "mesh_mesh") return peer("gimpact-miss");
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

const std::vector<std::string> kVerdictColumns = {"agree", "within_tolerance", "peer_wrong", "crux_wrong",
                                                  "unsupported", "error", "no_arbiter"};

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
  j["crux_wrong"] = cruxWrong;
  j["findings"] = J(findings);
  j["error_examples"] = J(exampleErrors);
  return j;
}

void DiffSummary::print(std::ostream& out) const {
  std::set<std::string> backends;
  for (const auto& [op, perBackend] : table)
    for (const auto& [b, counts] : perBackend) backends.insert(b);
  out << "crux diff: " << cases << " cases in " << std::fixed << std::setprecision(1) << seconds << " s\n";
  out << "per op x backend (exact: answered / - / - / - / unsupported / error): agree / within tolerance / peer wrong / crux wrong / unsupported / error / no arbiter\n";
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
                                 std::pair{"within tolerance, by reason", &toleranceCauses}}) {
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

  DiffRunner runner;
  const WorldTolerance exactTol = runner.tolerance("exact");
  DiffSummary summary;
  std::map<std::string, int> written;  // shrunk cases per (backend, op, verdict, cause)
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  double lastDraw = -1;
  for (std::uint64_t index = 0;; ++index) {
    if (options.seconds > 0 ? elapsed() >= options.seconds : index >= options.cases) break;
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
      if (!e.empty() && !summary.exampleErrors.count("exact." + c.op))
        summary.exampleErrors["exact." + c.op] = e + " <- " + c.query;
    }
    for (const auto& backend : backends) {
      const WorldTolerance tol = runner.tolerance(backend);
      const Answer got = runner.run(c, backend);
      const Classification k = classifyAnswer(c, backend, got, exact, tol, exactTol, probeExact);
      ++summary.table[c.op][backend][std::string(verdictName(k.verdict))];
      if (k.verdict == Verdict::PeerWrong) ++summary.peerCauses[backend][k.cause];
      if (k.verdict == Verdict::WithinTolerance) ++summary.toleranceCauses[backend][k.cause];
      if (k.verdict == Verdict::CruxWrong) ++summary.cruxWrong;
      if (k.verdict == Verdict::Error && !summary.exampleErrors.count(backend + "." + c.op))
        summary.exampleErrors[backend + "." + c.op] = k.detail + " <- " + c.query;
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
        return classifyAnswer(t, backend, g, e, tol, exactTol, probe);
      };
      const DiffCase small = shrinkCase(c, k, reclassify, c.sharedSetup ? 60 : 300);
      const Answer smallExact = runner.run(small, "exact"), smallGot = runner.run(small, backend);
      const std::string name = kind + "." + std::to_string(c.seed) + "-" + std::to_string(c.index);
      J meta = J{{"name", name},         {"family", c.family},
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

int runDiffCommand(const DiffOptions& options, std::ostream& out, std::ostream& err) {
  const DiffSummary summary = runDiff(options, err);
  if (!options.quiet) summary.print(out);
  if (!options.jsonFile.empty()) {
    std::ofstream json(options.jsonFile);
    json << summary.toJson().dump(2) << '\n';
    if (!json) throw InvalidInput("json: cannot write \"" + options.jsonFile + "\"");
  }
  return summary.cruxWrong > 0 ? 1 : 0;
}

}  // namespace crux::cli
