#pragma once
/// @file batch.hpp  `crux batch`: the JSON Lines protocol of /work/shared/contracts/batch-protocol.md
/// (documented for users in docs/batch.md), as a library so tests drive it without processes.
///
/// One request object per input line, one answer object per input line, in input order. Every
/// op is answered by a crux::CollisionWorld made by crux::makeWorld(backend): a request is
/// dispatched through one table op-name -> handler (the same for every backend) whose handler
/// reads the fields, resolves names and calls the world; an op the world does not supports()
/// answers "unsupported: <op> on <backend>" (crux::Unsupported's text), and a peer's failure
/// answers crux::BackendFailure's text.

#include <crux/mesh/mesh.hpp>
#include <crux/world/collision_world.hpp>

#include <nlohmann/json.hpp>

#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace crux::cli {

/// A request as parsed (keys sorted; duplicate keys: the last one wins).
using Json = nlohmann::json;
/// An answer: keys in insertion order, so "id" and "op" come first.
using Answer = nlohmann::ordered_json;

/// The library that answers the queries (a crux::makeWorld backend name).
enum class Backend { Native, Fcl, Bullet, Exact };

/// The protocol name of a backend ("native", "fcl", "bullet", "exact").
std::string_view backendName(Backend backend);
/// The backend called `name`, or nothing for an unknown name.
std::optional<Backend> parseBackend(std::string_view name);
/// Every backend name, in declaration order (for help texts and error messages).
std::vector<std::string_view> backendNames();

/// Options of one `crux batch` run.
struct BatchOptions {
  Backend backend = Backend::Native;
  /// Worker threads (>= 1). With N > 1 and a backend whose world allows concurrent queries
  /// (native), runBatch answers each run of consecutive query lines in parallel with oneTBB;
  /// the output is byte-identical to N = 1. Peer backends are answered serially.
  int threads = 1;
  /// The `crux` executable. When set, runBatch answers the peer backends (fcl, bullet) in a
  /// worker process (PeerWorker, apps/cli/peer_worker.hpp): a query on which the peer library
  /// aborts, crashes or exceeds timeoutSeconds gets "<backend> failed on <op>: <signal or
  /// timeout>" and every other line is answered. Empty: every backend answers in process.
  std::string workerExecutable;
  /// Time limit per line of a worker process, in seconds (> 0).
  double timeoutSeconds = 30;
};

struct BatchState;

/// Read-only view of the meshes a batch defined (`mesh`, `load_mesh`), by name, as its world
/// holds them.
class BatchMeshes {
 public:
  explicit BatchMeshes(const BatchState* state) : state_(state) {}
  /// 1 when a mesh named `name` is defined, else 0.
  std::size_t count(std::string_view name) const;
  /// The mesh named `name`; throws std::out_of_range when there is none.
  const std::shared_ptr<const Mesh>& at(std::string_view name) const;

 private:
  friend struct BatchState;
  const BatchState* state_;
};

/// Read-only view of the batch's scene: how many models it holds.
class BatchScene {
 public:
  explicit BatchScene(const BatchState* state) : state_(state) {}
  std::size_t size() const;

 private:
  friend struct BatchState;
  const BatchState* state_;
};

/// State that lives for a whole batch: the world of the chosen backend (meshes, models, the
/// scene) and the model names the protocol uses, mapped to the world's handles (the batch
/// layer resolves names itself so that errors name the request's field).
struct BatchState {
  /// Makes the world with crux::makeWorld(backendName(opts.backend)); throws crux::InvalidInput
  /// when that backend is not built.
  explicit BatchState(BatchOptions opts = {});
  BatchState(BatchState&& other) noexcept;
  BatchState& operator=(BatchState&& other) noexcept;
  BatchState(const BatchState&) = delete;
  BatchState& operator=(const BatchState&) = delete;
  ~BatchState();

  BatchOptions options;
  std::unique_ptr<CollisionWorld> world;
  /// Live model names -> handles, and back.
  std::map<std::string, ModelHandle, std::less<>> models;
  std::map<ModelHandle, std::string> modelNames;
  /// The name of a model the world reported in answering `op`; a handle naming no model is the
  /// backend's failure (BackendFailure).
  const std::string& modelName(ModelHandle model, WorldOp op) const;
  /// Views for callers and tests (they follow the world).
  BatchMeshes meshes{this};
  BatchScene scene{this};
};

/// Answers one request: reads the fields it needs from `request` and adds the answer fields
/// to `answer` (which already holds the echoed "id" and "op"). Throws crux::InvalidInput,
/// naming the field, for a missing, ill-typed or invalid field; the dispatcher turns that
/// into an error answer.
using OpHandler = std::function<void(const Json& request, Answer& answer, BatchState& state)>;
/// Handlers by op name (one table for every backend: each handler calls the world).
using OpTable = std::map<std::string, OpHandler, std::less<>>;

/// Every op the protocol defines, sorted. An op outside this list is "unknown"; an op in it
/// that the backend's world does not supports() is "unsupported".
const std::vector<std::string_view>& protocolOps();
/// The handler table (built once, immutable; every protocol op).
const OpTable& opTable();
/// The same table, whatever the backend (kept for callers of the per-backend form).
const OpTable& opTable(Backend backend);
/// Whether `op` changes the batch's state or caches (mesh, load_mesh, add_model,
/// set_transform, set_parent, remove_model, and scene_pairs, which updates the broad phase's
/// pair cache): such lines are barriers for --threads.
bool isBarrierOp(std::string_view op);

/// Answers one input line (without its line terminator; a trailing '\r' is ignored). Never
/// throws for bad input: a malformed line, an unknown op or a bad field gives an answer with
/// an "error" member. The answer echoes the request's "id" and "op" when present.
Answer answerLine(const std::string& line, BatchState& state);

/// Writes `answer` as one line of compact JSON (doubles in nlohmann::json's round-trip-exact
/// shortest form; invalid UTF-8 replaced by U+FFFD) followed by '\n'.
void writeAnswer(std::ostream& out, const Answer& answer);

/// Runs a batch: answers every line of `in` on `out`, one line each, in order, flushing each
/// answer as soon as it and every answer before it are written (so a crash loses no answer
/// already computed in order). With a workerExecutable, fcl and bullet answer in a worker
/// process (see BatchOptions::workerExecutable).
/// With options.threads > 1 and a world whose concurrentQueries() is true, it reads windows of
/// the lines already available (std::streambuf::in_avail; at least one, up to kBatchWindow), answers each run of consecutive non-barrier lines in parallel
/// (oneTBB, at most `threads` workers, after CollisionWorld::prepareConcurrentQueries()) and
/// each barrier line alone, and writes the answers in input order: the output is identical to
/// threads = 1. Returns 0 when `in` was read to its end and every answer was written, 1 when
/// reading or writing failed. Throws crux::InvalidInput for invalid options (threads < 1,
/// timeoutSeconds <= 0, a backend not built).
int runBatch(std::istream& in, std::ostream& out, const BatchOptions& options);

/// The error answer (one line of text) of a request line on which `backend`'s worker process
/// failed: the request's "id" and "op" echoed and "error": "<backend> failed on <op>:
/// <failure>" (crux::BackendFailure's text).
std::string failureAnswer(const std::string& line, Backend backend, const std::string& failure);

/// `crux batch --worker`: the worker side of PeerWorker's protocol (apps/cli/peer_worker.hpp),
/// answering in process with one BatchState per slot, every reply flushed. Returns 0 at the end
/// of `in`, 1 when writing failed.
int runWorker(std::istream& in, std::ostream& out, const BatchOptions& options);

/// Lines runBatch reads ahead with threads > 1.
inline constexpr std::size_t kBatchWindow = 4096;

}  // namespace crux::cli
