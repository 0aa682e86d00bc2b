#pragma once
/// @file diff.hpp  `crux diff`: the differential fuzzer (user documentation: docs/diff.md).
///
/// Generates cases in named families, runs each through the batch protocol (answerLine, one fresh
/// BatchState per backend, so every case is replayable with `crux batch --backend X`), compares
/// every backend's answer with the exact (CGAL) backend's, classifies each disagreement, shrinks the
/// interesting ones to minimal reproductions and summarises the run per op × backend.
///
/// A case is a short list of protocol request lines: setup lines (`mesh`, `load_mesh`,
/// `add_model`, ...) then one query line. Classification of a backend's answer against the
/// arbiter's (the rules are in docs/diff.md):
/// - agree: equal booleans and lists, numbers within the two backends' declared tolerances;
/// - within tolerance: the case is within the backend's declared tolerance τ of a boundary —
///   moving the query shape by an offset in {-τ,0,τ}³ changes the exact answer — or it is
///   outside the backend's declared working range (shapes smaller than its minFeature);
///   never for native booleans on integer-grid cases (those must be exact);
/// - crux wrong (native) / peer wrong (fcl, bullet, with a likely cause);
/// - unsupported, error (an error answer where the arbiter answered).

#include "cli/batch.hpp"

#include <crux/world/collision_world.hpp>

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace crux::cli {

/// One generated case: setup lines then one query line, all protocol JSON.
struct DiffCase {
  std::string family;
  std::uint64_t seed = 0;   ///< the run's seed
  std::uint64_t index = 0;  ///< the case's index in the run (its own seed derives from both)
  std::string op;           ///< the query's op
  std::vector<std::string> setup;
  std::string query;
  /// Every coordinate is an integer and every transform maps the grid onto itself: native's
  /// booleans must equal exact's with no tolerance.
  bool exactGrid = false;
  /// The setup only loads real meshes (load_mesh lines) and is shared by many cases: runners
  /// may answer the query in a state prepared once.
  bool sharedSetup = false;
  /// Typical size of the case's shapes (compared with a backend's minFeature).
  double featureSize = 1;
  /// Largest coordinate magnitude of meshes loaded from files (the lines do not show it).
  double extraMagnitude = 0;
};

/// The verdict on one backend's answer to a case.
enum class Verdict { Agree, WithinTolerance, PeerWrong, CruxWrong, Unsupported, Error, NoArbiter, PeerFailed };
/// "agree", "within_tolerance", "peer_wrong", "crux_wrong", "unsupported", "error", "no_arbiter",
/// "peer_failed" (the peer library failed on the case: it threw, or its worker process crashed
/// or ran out of time).
std::string_view verdictName(Verdict verdict);

/// A verdict with its likely cause ("" when none applies) and a one-line detail.
struct Classification {
  Verdict verdict = Verdict::Agree;
  std::string cause;
  std::string detail;
  friend bool operator==(const Classification& a, const Classification& b) {
    return a.verdict == b.verdict && a.cause == b.cause;
  }
};

/// Every family name, in generation order: general, grid, coplanar, touching, degenerate,
/// near_degenerate, sliver, huge, tiny, transformed, mesh, hierarchy, scene.
const std::vector<std::string_view>& diffFamilies();
/// The query ops a family generates.
const std::vector<std::string_view>& diffFamilyOps(std::string_view family);

/// Inputs of case generation that do not change between cases.
struct DiffGenerator {
  /// Directory holding the real meshes (data/meshes); empty: the mesh family uses generated
  /// meshes only.
  std::string meshDir;
  /// Query ops to generate (empty: all).
  std::vector<std::string> ops;
  /// Real meshes loaded once (name -> mesh), filled lazily by generateCase.
  std::map<std::string, std::shared_ptr<const Mesh>, std::less<>> realMeshes;
};

/// The per-case seed of case `index` in a run seeded `seed` (SplitMix64 of both).
std::uint64_t caseSeed(std::uint64_t seed, std::uint64_t index);
/// Generates case `index` of `family` for a run seeded `seed`; nothing when the family has no
/// op in the generator's op filter. Deterministic in (family, seed, index, generator options).
std::optional<DiffCase> generateCase(std::string_view family, std::uint64_t seed, std::uint64_t index,
                                     DiffGenerator& generator);

/// Largest coordinate magnitude of a case (points, radii, plane offsets, translations;
/// directions, normals, rotations and indices excluded), at least extraMagnitude.
double caseMagnitude(const DiffCase& c);
/// The case with its query shape (or, for scene_pairs, the model named `model`, by default the
/// last model added) translated by `offset`; nothing when the op has no shape to move (children)
/// or the model is not placed by any line.
std::optional<DiffCase> translatedCase(const DiffCase& c, const Vec3d& offset, std::string_view model = {});

/// Whether two answers to `queryLine` agree: equal booleans and lists (a bounds-only
/// scene_query may answer a superset), numbers within `tolerance`. Error answers never agree.
bool answersAgree(const std::string& queryLine, const Answer& got, const Answer& exact, double tolerance);

/// Runs cases through the batch protocol, one BatchState per backend and case (shared-setup
/// cases reuse one prepared state per backend and setup).
class DiffRunner {
 public:
  /// With a `workerExecutable` (the `crux` executable), fcl and bullet answer in worker
  /// processes (PeerWorker) with a time limit of `timeoutSeconds` per line: a peer that aborts,
  /// crashes or hangs gives "<backend> failed on <op>: ..." for that case only. Without one,
  /// every backend answers in this process.
  explicit DiffRunner(std::string workerExecutable = {}, double timeoutSeconds = 2);
  ~DiffRunner();
  /// The answer of `backend` to the case's query; an error in a setup line is returned as the
  /// answer (its "error" prefixed with "setup: ").
  Answer run(const DiffCase& c, std::string_view backend);
  /// The declared tolerance of a backend (from its CollisionWorld).
  WorldTolerance tolerance(std::string_view backend);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Classifies `got` (the answer of `backend`) against `exact`, the arbiter's answer to the
/// same case. `probeExact` answers translated cases on the exact backend (used for the
/// within-tolerance and cause rules). `tol` is the backend's declared tolerance, `exactTol`
/// the arbiter's. `probePeer`, when given, answers other cases on `backend` itself (the
/// `absolute-epsilons` rule asks Bullet the case scaled by a power of two).
Classification classifyAnswer(const DiffCase& c, std::string_view backend, const Answer& got, const Answer& exact,
                              const WorldTolerance& tol, const WorldTolerance& exactTol,
                              const std::function<Answer(const DiffCase&)>& probeExact,
                              const std::function<Answer(const DiffCase&)>& probePeer = {});

/// Greedy shrinking: drops setup lines and mesh triangles, snaps numbers to 0, integers, fewer
/// mantissa bits and halves, keeping every change after which `classify` still gives `target`.
/// At most `budget` evaluations.
DiffCase shrinkCase(const DiffCase& c, const Classification& target,
                    const std::function<std::optional<Classification>(const DiffCase&)>& classify, int budget);

/// Options of one `crux diff` run.
struct DiffOptions {
  std::uint64_t seed = 1;
  /// Index of the first case: a run answers cases firstCase .. firstCase + cases - 1 of the
  /// sequence `seed` defines (each case derives from the seed and its index alone), so shards of
  /// a campaign are runs with consecutive ranges (docs/diff.md "Campaigns").
  std::uint64_t firstCase = 0;
  /// Number of cases; ignored when seconds > 0.
  std::uint64_t cases = 1000;
  /// Run for this many seconds instead of a fixed number of cases (0: use cases).
  double seconds = 0;
  std::vector<std::string> families;  ///< empty: all
  std::vector<std::string> ops;       ///< empty: all
  std::vector<std::string> backends;  ///< empty: every backend built; exact is always run
  std::string outDir;                 ///< write shrunk cases here ("" : do not)
  std::string jsonFile;               ///< write the summary as JSON here ("" : do not)
  /// A shard's directory ("" : none): started.json (the run's range) is written when the run
  /// starts, the shrunk cases go to DIR/findings and the summary to DIR/summary.json (written
  /// whole or not at all), unless outDir / jsonFile say otherwise.
  std::string shardDir;
  std::string meshDir;                ///< real meshes ("" : generated meshes only)
  bool quiet = false;                 ///< no text summary
  bool progress = false;              ///< draw a progress line on `err` (a terminal)
  int shrinkPerKind = 2;              ///< shrunk cases written per (backend, op, verdict, cause)
  /// The `crux` executable: fcl and bullet answer in worker processes (DiffRunner). Empty: in
  /// this process.
  std::string workerExecutable;
  double peerTimeoutSeconds = 2;      ///< time limit per line of a worker process
};

/// Counts of one run: per op and backend, per verdict; peer-wrong and within-tolerance causes
/// per backend; the shrunk cases written.
struct DiffSummary {
  std::uint64_t seed = 0;
  std::uint64_t firstCase = 0;       ///< the range answered: firstCase ..
  std::uint64_t requestedCases = 0;  ///< .. firstCase + requestedCases - 1 (0 with --seconds)
  std::vector<std::string> families, ops, backends;  ///< as run (ops empty: all)
  int shrinkPerKind = 2;
  std::uint64_t cases = 0;  ///< cases generated (the op filter skips some indices)
  double seconds = 0;
  std::map<std::string, std::map<std::string, std::map<std::string, std::uint64_t>>> table;  // op, backend, verdict
  std::map<std::string, std::map<std::string, std::uint64_t>> peerCauses;                    // backend, cause
  std::map<std::string, std::map<std::string, std::uint64_t>> toleranceCauses;               // backend, cause
  std::map<std::string, std::map<std::string, std::uint64_t>> peerFailures;  // backend, crash/timeout/exception
  std::vector<Answer> findings;  ///< crux-wrong and shrunk peer cases (metadata)
  std::uint64_t cruxWrong = 0;
  /// The first error answer per "backend.op" (with its case), for diagnosis, and that case's index.
  std::map<std::string, std::string> exampleErrors;
  std::map<std::string, std::uint64_t> exampleErrorCases;
  /// The summary as JSON (deterministic for a given seed and case count, except "seconds").
  Answer toJson() const;
  /// The summary written by toJson; throws InvalidInput naming the field for another shape.
  static DiffSummary fromJson(const Answer& json);
  /// The op × backend table and the causes as text.
  void print(std::ostream& out) const;
};

/// What `crux diff merge` found in one shard directory.
struct ShardStatus {
  std::string dir;
  /// "merged"; "duplicate" (the same range as a shard merged before it); "failed" (started.json
  /// but no summary: cancelled, crashed or still running); "missing" (neither file).
  std::string status;
  std::uint64_t firstCase = 0, requestedCases = 0;  ///< from summary.json or started.json
  double seconds = 0;
  std::uint64_t cases = 0;
};

/// A merged campaign: the summary over every merged shard, and what was wrong with the others.
struct MergedCampaign {
  DiffSummary summary;
  std::vector<ShardStatus> shards;
  /// Case ranges no merged shard answered, "K..L" (between and before merged ranges, and the
  /// ranges of failed shards), in order.
  std::vector<std::string> missingRanges;
  /// No shard missing or failed and no range left out.
  bool complete() const;
  /// The summary's text (DiffSummary::print), then a line per shard not merged and per range
  /// left out.
  void print(std::ostream& out) const;
  /// summary.toJson() with "shards" and "missing_cases" added.
  Answer toJson() const;
};

/// `crux diff merge DIR...`: adds the shards' op × backend tables and cause counts, joins their
/// findings in case order without duplicates (keeping, per kind, the first shrinkPerKind, as a
/// serial run does) and takes each first error example by case index, so that the merged summary
/// of shards covering 0..N-1 equals a serial run of N cases (except the times). Throws
/// InvalidInput when the shards ran different seeds, families, ops, backends or shrink limits,
/// or when their ranges overlap without being equal.
MergedCampaign mergeShards(const std::vector<std::string>& dirs);

/// `crux diff merge`: merges, prints (unless `quiet`), writes the merged summary to `jsonFile`
/// and copies the kept findings' files (`<name>.jsonl`, `<name>.json` from each shard's
/// findings/) to `outDir` (each when not empty). Returns 1 when a crux-wrong case was found,
/// 3 when a shard is missing or failed or a range is left out, else 0.
int runMergeCommand(const std::vector<std::string>& dirs, const std::string& jsonFile, const std::string& outDir,
                    bool quiet, std::ostream& out);

/// Writes `json` to `path` whole (a temporary file renamed over it); throws InvalidInput naming
/// the path when it cannot.
void writeJsonFile(const std::string& path, const Answer& json);

/// Runs the fuzzer. Returns the summary; throws InvalidInput for bad options (unknown family,
/// op or backend).
DiffSummary runDiff(const DiffOptions& options, std::ostream& err);

/// `crux diff`: runs, prints the summary on `out` (unless quiet), writes --json. Returns 1 when a
/// crux-wrong case was found, 0 otherwise.
int runDiffCommand(const DiffOptions& options, std::ostream& out, std::ostream& err);

}  // namespace crux::cli
