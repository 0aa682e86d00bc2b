#pragma once
/// @file batch.hpp  `crux batch`: the JSON Lines protocol of /work/shared/contracts/batch-protocol.md
/// (documented for users in docs/batch.md), as a library so tests drive it without processes.
///
/// One request object per input line, one answer object per input line, in input order. A
/// request is dispatched through a table op-name -> handler chosen by the backend; an op the
/// protocol names but the backend's table lacks answers "unsupported: <op> on <backend>".

#include <crux/mesh/mesh.hpp>
#include <crux/scene/scene.hpp>

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

/// The library that answers the queries. Only Native is implemented; the others are accepted
/// and answer every op with "unsupported: <op> on <backend>" until their oracle lands.
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
  /// Worker threads (>= 1). Accepted for forward compatibility; requests are answered
  /// sequentially for now (the answers would be identical and in the same order anyway).
  int threads = 1;
};

/// State that lives for a whole batch: meshes and models by name, and the scene.
struct BatchState {
  explicit BatchState(BatchOptions opts = {}) : options(opts) {}
  BatchOptions options;
  /// Meshes defined by `mesh` and `load_mesh`, by name. Meshes are immutable and shared:
  /// redefining a name replaces the entry for later requests, while anything already holding
  /// the old pointer keeps the old mesh. A failed definition leaves the entry unchanged.
  std::map<std::string, std::shared_ptr<const Mesh>, std::less<>> meshes;
  /// The models of `add_model` (one scene per batch, dynamic AABB tree broad phase).
  Scene scene;
  /// Model names -> ids in `scene`, and back (modelNames[id]; empty for unused ids).
  std::map<std::string, ModelId, std::less<>> models;
  std::vector<std::string> modelNames;
};

/// Answers one request: reads the fields it needs from `request` and adds the answer fields
/// to `answer` (which already holds the echoed "id" and "op"). Throws crux::InvalidInput,
/// naming the field, for a missing, ill-typed or invalid field; the dispatcher turns that
/// into an error answer.
using OpHandler = std::function<void(const Json& request, Answer& answer, BatchState& state)>;
/// Handlers by op name, for one backend.
using OpTable = std::map<std::string, OpHandler, std::less<>>;

/// Every op the protocol defines, sorted. An op outside this list is "unknown"; an op in it
/// that a backend's table lacks is "unsupported".
const std::vector<std::string_view>& protocolOps();
/// The handler table of `backend` (built once, immutable).
const OpTable& opTable(Backend backend);

/// Answers one input line (without its line terminator; a trailing '\r' is ignored). Never
/// throws for bad input: a malformed line, an unknown op or a bad field gives an answer with
/// an "error" member. The answer echoes the request's "id" and "op" when present.
Answer answerLine(const std::string& line, BatchState& state);

/// Writes `answer` as one line of compact JSON (doubles in nlohmann::json's round-trip-exact
/// shortest form; invalid UTF-8 replaced by U+FFFD) followed by '\n'.
void writeAnswer(std::ostream& out, const Answer& answer);

/// Runs a batch: answers every line of `in` on `out`, one line each, in order, and flushes.
/// Returns 0 when `in` was read to its end and every answer was written, 1 when reading or
/// writing failed. Throws crux::InvalidInput for invalid options (threads < 1).
int runBatch(std::istream& in, std::ostream& out, const BatchOptions& options);

}  // namespace crux::cli
