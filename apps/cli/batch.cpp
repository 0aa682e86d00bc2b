#include "cli/batch.hpp"

#include "cli/json_codec.hpp"
#include "cli/mesh_ops.hpp"
#include "cli/narrowphase_ops.hpp"
#include "cli/peer_worker.hpp"
#include "cli/primitive_ops.hpp"
#include "cli/scene_ops.hpp"

#include <crux/error.hpp>
#include <world_factory.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdlib>
#include <mutex>
#include <istream>
#include <ostream>
#include <stdexcept>

namespace crux::cli {
namespace {

constexpr std::array<std::string_view, 4> kBackendNames = {"native", "fcl", "bullet", "exact"};

/// Builds the request DOM from nlohmann's SAX events while tracking the protocol path of the
/// value being parsed, so that a parse failure inside a value (a number literal that overflows
/// double, such as 1e400) is reported naming its field, and the "id" and "op" read before the
/// failure can still be echoed.
class RequestBuilder {
 public:
  using number_integer_t = Json::number_integer_t;
  using number_unsigned_t = Json::number_unsigned_t;
  using number_float_t = Json::number_float_t;
  using string_t = Json::string_t;
  using binary_t = Json::binary_t;

  Json root;  ///< The request; after a failure, the part parsed so far.

  /// Set when parsing failed.
  struct Failure {
    int id = 0;              ///< nlohmann exception id (406: number overflow).
    std::string what;        ///< nlohmann's message.
    std::string token;       ///< The last token read.
    std::string path;        ///< Protocol path of the value being parsed ("" = the request).
  };
  std::optional<Failure> failure;

  bool null() { return put(nullptr); }
  bool boolean(bool value) { return put(value); }
  bool number_integer(number_integer_t value) { return put(value); }
  bool number_unsigned(number_unsigned_t value) { return put(value); }
  bool number_float(number_float_t value, const string_t&) { return put(value); }
  bool string(string_t& value) { return put(std::move(value)); }
  bool binary(binary_t& value) { return put(Json::binary(std::move(value))); }
  bool start_object(std::size_t) { return open(Json::object()); }
  bool start_array(std::size_t) { return open(Json::array()); }
  bool key(string_t& name) {
    key_ = std::move(name);
    return true;
  }
  bool end_object() { return close(); }
  bool end_array() { return close(); }
  bool parse_error(std::size_t, const std::string& lastToken, const Json::exception& ex) {
    failure = Failure{ex.id, ex.what(), lastToken, currentPath()};
    return false;
  }

 private:
  /// Where a value sits in its container: a member key or an array index.
  struct Slot {
    bool isMember = false;
    std::string key;
    std::size_t index = 0;
  };
  std::vector<Json*> open_;  // open containers, innermost last
  std::vector<Slot> slots_;  // where each open container sits in the one before it
  std::string key_;          // key of the next value in the innermost object

  Slot currentSlot() const {
    const Json& top = *open_.back();
    return top.is_object() ? Slot{true, key_, 0} : Slot{false, {}, top.size()};
  }
  /// The path of the value being parsed; built only on failure (linear in the depth).
  std::string currentPath() const {
    if (open_.empty()) return "";
    std::string path;
    const auto append = [&path](const Slot& slot) {  // as memberPath / elementPath, in place
      if (slot.isMember) {
        if (!path.empty()) path += '.';
        path += slot.key;
      } else {
        path += '[' + std::to_string(slot.index) + ']';
      }
    };
    for (std::size_t i = 1; i < slots_.size(); ++i) append(slots_[i]);
    append(currentSlot());
    return path;
  }
  Json* place(Json value) {
    if (open_.empty()) {
      root = std::move(value);
      return &root;
    }
    Json& top = *open_.back();
    if (top.is_object()) {
      Json& slot = top[key_];  // a repeated key overwrites: the last one wins
      slot = std::move(value);
      return &slot;
    }
    top.push_back(std::move(value));
    return &top.back();
  }
  bool put(Json value) {
    place(std::move(value));
    return true;
  }
  bool open(Json container) {
    Slot slot = open_.empty() ? Slot{} : currentSlot();
    open_.push_back(place(std::move(container)));
    slots_.push_back(std::move(slot));
    return true;
  }
  bool close() {
    open_.pop_back();
    slots_.pop_back();
    return true;
  }
};

/// nlohmann's message without its "[json.exception.parse_error.101] " prefix.
std::string parseMessage(const std::string& what) {
  const auto end = what.find("] ");
  return (what.rfind("[json.exception.", 0) == 0 && end != std::string::npos) ? what.substr(end + 2) : what;
}

/// An answer carrying only the echoed id/op (when the request had them) and `message`.
Answer errorAnswer(const Json& request, const std::string& message) {
  Answer answer = Answer::object();
  if (request.is_object()) {
    // id and op are echoed as given when they are scalars. An array or object there is an error
    // already (both must be strings) and is not echoed: the copy would recurse once per level of
    // nesting, and a line of ~80,000 brackets overflowed the stack.
    for (const char* key : {"id", "op"})
      if (const auto field = request.find(key); field != request.end() && !field->is_structured())
        answer[key] = Answer(*field);
  }
  answer["error"] = message;
  return answer;
}

bool isBlank(std::string_view s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; });
}

OpTable buildTable() {
  OpTable table;
  addPrimitiveOps(table);
  addMeshOps(table);
  addSceneOps(table);
  addNarrowPhaseOps(table);
  return table;
}

/// A line parsed into its request, or the answer already decided (a malformed line, a bad
/// "id" or "op", an unknown op).
struct ParsedLine {
  Json request;
  std::optional<Answer> answer;
  std::string op;  ///< the protocol op when `answer` is empty
};

ParsedLine parseLine(const std::string& rawLine) {
  ParsedLine parsed;
  std::string_view line = rawLine;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (isBlank(line)) {
    parsed.answer = errorAnswer(Json(), "empty line");
    return parsed;
  }
  RequestBuilder builder;
  Json::sax_parse(line.begin(), line.end(), &builder);
  parsed.request = std::move(builder.root);
  const Json& request = parsed.request;
  // The parser takes a NUL byte for the end of its input and would ignore the rest of the line
  // (within a string a NUL is a control character it reports itself).
  if (const std::size_t nul = line.find('\0'); nul != std::string_view::npos && !builder.failure) {
    parsed.answer = errorAnswer(request, "invalid JSON: NUL byte at column " + std::to_string(nul + 1));
    return parsed;
  }
  if (builder.failure) {
    const auto& f = *builder.failure;
    if (f.id == 406) {  // out_of_range.406: a number literal beyond double
      parsed.answer = errorAnswer(request, (f.path.empty() ? std::string("request") : f.path) + ": number " +
                                               f.token + " overflows double");
    } else {
      parsed.answer = errorAnswer(request, "invalid JSON: " + parseMessage(f.what));
    }
    return parsed;
  }
  if (!request.is_object()) {
    parsed.answer = errorAnswer(request, std::string("request: expected a JSON object, got ") + request.type_name());
    return parsed;
  }
  if (const auto id = request.find("id"); id != request.end() && !id->is_string()) {
    parsed.answer = errorAnswer(request, std::string("id: expected a string, got ") + id->type_name());
    return parsed;
  }
  const auto opField = request.find("op");
  if (opField == request.end()) {
    parsed.answer = errorAnswer(request, "op: missing field");
    return parsed;
  }
  if (!opField->is_string()) {
    parsed.answer = errorAnswer(request, std::string("op: expected a string, got ") + opField->type_name());
    return parsed;
  }
  const std::string& op = opField->get_ref<const std::string&>();
  const auto& ops = protocolOps();
  if (!std::binary_search(ops.begin(), ops.end(), std::string_view(op))) {
    parsed.answer = errorAnswer(request, "op: unknown op \"" + op + "\"");
    return parsed;
  }
  parsed.op = op;
  return parsed;
}

/// Answers a parsed line through the world of `state`.
Answer answerParsed(const ParsedLine& parsed, BatchState& state) {
  if (parsed.answer) return *parsed.answer;
  const Json& request = parsed.request;
  try {
    const std::optional<WorldOp> op = parseOp(parsed.op);
    if (!op) return errorAnswer(request, "internal error: op \"" + parsed.op + "\" has no world op");
    if (!state.world->supports(*op)) return errorAnswer(request, Unsupported(*op, state.world->backend()).what());
    const OpTable& table = opTable();
    const auto handler = table.find(parsed.op);
    if (handler == table.end()) return errorAnswer(request, "internal error: no handler for \"" + parsed.op + "\"");

    Answer answer = Answer::object();
    if (const auto id = request.find("id"); id != request.end()) answer["id"] = Answer(*id);
    answer["op"] = parsed.op;
    handler->second(request, answer, state);
    return answer;
  } catch (const InvalidInput& e) {
    return errorAnswer(request, e.what());
  } catch (const Unsupported& e) {
    return errorAnswer(request, e.what());
  } catch (const BackendFailure& e) {
    return errorAnswer(request, e.what());
  } catch (const std::exception& e) {
    return errorAnswer(request, std::string("internal error: ") + e.what());
  }
}

/// The answer to a line, never throwing (a failure to build the answer itself, such as
/// std::bad_alloc, becomes an error answer).
Answer answerSafely(const ParsedLine& parsed, BatchState& state) {
  try {
    return answerParsed(parsed, state);
  } catch (const std::exception& e) {
    return errorAnswer(Json(), std::string("internal error: ") + e.what());
  }
}

/// The output line of an answer (without its '\n'), as writeAnswer writes it.
std::string answerText(const Answer& answer) { return answer.dump(-1, ' ', false, Answer::error_handler_t::replace); }

/// The answers of a window of lines, written in input order as soon as each answer and all
/// before it are done (from whichever thread completes the prefix), each write flushed: a crash
/// loses no answer that could have been written.
class OrderedOutput {
 public:
  OrderedOutput(std::ostream& out, std::vector<std::string>& answers) : out_(out), answers_(answers) {}
  /// Starts a window of `n` answers.
  void reset(std::size_t n) {
    if (capacity_ < n) {
      done_ = std::make_unique<std::atomic<bool>[]>(n);
      capacity_ = n;
    }
    for (std::size_t i = 0; i < n; ++i) done_[i].store(false, std::memory_order_relaxed);
    size_ = n;
    next_ = 0;
  }
  /// answers[i] is final: writes it and the answers after it that are done, unless another
  /// thread is writing (that thread, or the next finish, writes them).
  void finished(std::size_t i) {
    done_[i].store(true, std::memory_order_release);
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (lock) drain();
  }
  /// Writes every done answer in order; at the end of a window, all of them. False when
  /// writing failed.
  bool drain() {
    const std::size_t first = next_;
    while (next_ < size_ && done_[next_].load(std::memory_order_acquire)) out_ << answers_[next_++] << '\n';
    if (next_ != first) out_.flush();
    return bool(out_);
  }
  bool finish() {
    std::lock_guard<std::mutex> lock(mutex_);
    return drain() && next_ == size_;
  }

 private:
  std::ostream& out_;
  std::vector<std::string>& answers_;
  std::unique_ptr<std::atomic<bool>[]> done_;
  std::size_t capacity_ = 0, size_ = 0, next_ = 0;
  std::mutex mutex_;
};

/// Answers lines [begin, end) of a window, all queries, in parallel (the world was prepared),
/// serialising each answer on its worker too.
void answerInParallel(const std::vector<ParsedLine>& parsed, std::vector<std::string>& answers, std::size_t begin,
                      std::size_t end, BatchState& state, tbb::task_arena& arena, OrderedOutput& output) {
  if (end - begin < 2) {
    for (std::size_t i = begin; i < end; ++i) {
      answers[i] = answerText(answerSafely(parsed[i], state));
      output.finished(i);
    }
    return;
  }
  state.world->prepareConcurrentQueries();
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        answers[i] = answerText(answerSafely(parsed[i], state));
        output.finished(i);
      }
    });
  });
}

/// runBatch with threads > 1 on a world that allows concurrent queries.
int runParallel(std::istream& in, std::ostream& out, BatchState& state, int threads) {
  tbb::task_arena arena(threads);
  std::vector<std::string> lines;
  std::vector<ParsedLine> parsed;
  std::vector<std::string> answers;
  OrderedOutput output(out, answers);
  lines.reserve(kBatchWindow);
  for (bool more = true; more;) {
    // a window: the lines already available (at least one, at most kBatchWindow), so that a
    // client waiting for each answer before it writes the next line is answered
    lines.clear();
    std::string line;
    while (lines.size() < kBatchWindow) {
      if (!lines.empty() && in.rdbuf()->in_avail() <= 0) break;
      if (!std::getline(in, line)) {
        more = false;
        break;
      }
      lines.push_back(std::move(line));
    }
    if (lines.empty()) break;
    parsed.assign(lines.size(), ParsedLine{});
    answers.assign(lines.size(), std::string());
    output.reset(lines.size());
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lines.size()),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            try {
                              parsed[i] = parseLine(lines[i]);
                            } catch (const std::exception& e) {
                              parsed[i].answer = errorAnswer(Json(), std::string("internal error: ") + e.what());
                            }
                          }
                        });
    });
    std::size_t runStart = 0;
    for (std::size_t i = 0; i < parsed.size(); ++i) {
      if (parsed[i].answer || !isBarrierOp(parsed[i].op)) continue;
      answerInParallel(parsed, answers, runStart, i, state, arena, output);
      answers[i] = answerText(answerSafely(parsed[i], state));
      output.finished(i);
      runStart = i + 1;
    }
    answerInParallel(parsed, answers, runStart, parsed.size(), state, arena, output);
    if (!output.finish()) return 1;
  }
  out.flush();
  return (in.bad() || !out) ? 1 : 0;
}

/// Whether `backend` runs in a worker process when BatchOptions::workerExecutable is set.
bool isolatedBackend(Backend backend) { return backend == Backend::Fcl || backend == Backend::Bullet; }

/// runBatch for a peer backend in a worker process (PeerWorker), one line at a time.
int runIsolated(std::istream& in, std::ostream& out, const BatchOptions& options) {
  PeerWorker worker({options.workerExecutable, options.backend, options.timeoutSeconds,
                     std::max(options.timeoutSeconds, 60.0)});
  std::string line;
  std::vector<std::string> one(1);
  while (std::getline(in, line)) {
    one[0] = std::move(line);
    out << worker.answer(one).front() << '\n';
    out.flush();
    if (!out) return 1;
  }
  out.flush();
  return (in.bad() || !out) ? 1 : 0;
}

}  // namespace

std::string_view backendName(Backend backend) { return kBackendNames[static_cast<std::size_t>(backend)]; }

std::optional<Backend> parseBackend(std::string_view name) {
  for (std::size_t i = 0; i < kBackendNames.size(); ++i)
    if (kBackendNames[i] == name) return static_cast<Backend>(i);
  return std::nullopt;
}

std::vector<std::string_view> backendNames() { return {kBackendNames.begin(), kBackendNames.end()}; }

const std::vector<std::string_view>& protocolOps() {
  static const std::vector<std::string_view> ops = [] {
    std::vector<std::string_view> v = {
        // primitives
        "closest_point_triangle", "triangle_sphere", "triangle_aabb", "triangle_obb", "triangle_plane",
        "triangle_triangle", "ray_triangle", "segment_triangle",
        // meshes
        "mesh", "load_mesh", "mesh_ray", "mesh_segment", "mesh_sphere", "mesh_aabb", "mesh_obb", "mesh_plane",
        "mesh_triangle", "mesh_mesh",
        // models
        "add_model", "set_transform", "set_parent", "remove_model", "model_ray", "model_segment",
        "model_sphere", "model_aabb", "model_obb", "model_plane", "model_triangle", "children",
        // scene
        "scene_ray", "scene_query", "scene_pairs",
        // narrow phase and volumes (beyond the shared contract, see docs/batch.md)
        "contacts", "distance", "mesh_distance", "model_distance", "point_inside",
        // shape casts (docs/batch.md)
        "cast", "model_cast", "scene_cast"};
    std::sort(v.begin(), v.end());
    return v;
  }();
  return ops;
}

const OpTable& opTable() {
  static const OpTable table = buildTable();
  return table;
}

const OpTable& opTable(Backend) { return opTable(); }

bool isBarrierOp(std::string_view op) {
  static constexpr std::array<std::string_view, 7> kBarriers = {
      "mesh", "load_mesh", "add_model", "set_transform", "set_parent", "remove_model", "scene_pairs"};
  return std::find(kBarriers.begin(), kBarriers.end(), op) != kBarriers.end();
}

// ---- BatchState -----------------------------------------------------------------------------------

BatchState::BatchState(BatchOptions opts) : options(opts), world(makeWorld(backendName(opts.backend))) {}

const std::string& BatchState::modelName(ModelHandle model, WorldOp op) const {
  const auto it = modelNames.find(model);
  if (it == modelNames.end())
    throw BackendFailure(op, world->backend(),
                         "reported model handle " + std::to_string(model.index) + ", which names no model");
  return it->second;
}

BatchState::BatchState(BatchState&& other) noexcept
    : options(other.options),
      world(std::move(other.world)),
      models(std::move(other.models)),
      modelNames(std::move(other.modelNames)) {}

BatchState& BatchState::operator=(BatchState&& other) noexcept {
  options = other.options;
  world = std::move(other.world);
  models = std::move(other.models);
  modelNames = std::move(other.modelNames);
  return *this;
}

BatchState::~BatchState() = default;

std::size_t BatchMeshes::count(std::string_view name) const {
  return state_->world && state_->world->findMesh(name) ? 1 : 0;
}

const std::shared_ptr<const Mesh>& BatchMeshes::at(std::string_view name) const {
  const auto handle = state_->world ? state_->world->findMesh(name) : std::nullopt;
  if (!handle) throw std::out_of_range("no mesh named \"" + std::string(name) + "\"");
  return state_->world->sharedMesh(*handle);
}

std::size_t BatchScene::size() const { return state_->models.size(); }

Answer answerLine(const std::string& line, BatchState& state) { return answerSafely(parseLine(line), state); }

void writeAnswer(std::ostream& out, const Answer& answer) { out << answerText(answer) << '\n'; }

int runBatch(std::istream& in, std::ostream& out, const BatchOptions& options) {
  if (options.threads < 1)
    throw InvalidInput("threads: must be at least 1, got " + std::to_string(options.threads));
  if (!(options.timeoutSeconds > 0))
    throw InvalidInput("timeout: must be positive, got " + std::to_string(options.timeoutSeconds));
  BatchState state(options);
  if (!options.workerExecutable.empty() && isolatedBackend(options.backend)) return runIsolated(in, out, options);
  if (options.threads > 1 && state.world->concurrentQueries()) return runParallel(in, out, state, options.threads);
  std::string line;
  while (std::getline(in, line)) {
    writeAnswer(out, answerLine(line, state));
    out.flush();  // streamed: a crash later loses no answer written so far
    if (!out) return 1;
  }
  out.flush();
  return (in.bad() || !out) ? 1 : 0;
}

std::string failureAnswer(const std::string& line, Backend backend, const std::string& failure) {
  const ParsedLine parsed = parseLine(line);
  const std::string& op = parsed.op;
  const std::optional<WorldOp> worldOp = parseOp(op);
  const std::string message = worldOp ? BackendFailure(*worldOp, backendName(backend), failure).what()
                                      : std::string(backendName(backend)) + " failed: " + failure;
  return answerText(errorAnswer(parsed.request, message));
}

int runWorker(std::istream& in, std::ostream& out, const BatchOptions& options) {
  BatchOptions inProcess = options;
  inProcess.workerExecutable.clear();
  inProcess.threads = 1;
  std::map<int, BatchState> slots;
  BatchState* state = nullptr;
  out << "ready\n";
  out.flush();
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const char tag = line[0];
    if (tag == 'r' || tag == 's') {
      const int slot = std::atoi(line.c_str() + 1);
      auto it = slots.find(slot);
      if (it == slots.end()) it = slots.emplace(slot, BatchState(inProcess)).first;
      else if (tag == 'r') it->second = BatchState(inProcess);
      state = &it->second;
      out << "ok\n";
    } else if (tag == 'q') {
      if (!state) state = &slots.emplace(0, BatchState(inProcess)).first->second;
      const ParsedLine parsed = parseLine(line.substr(1));
      const Answer answer = answerSafely(parsed, *state);
      const bool changed = !parsed.answer && isBarrierOp(parsed.op) && parsed.op != "scene_pairs" &&
                           !answer.contains("error");
      out << (changed ? '+' : '=') << answerText(answer) << '\n';
    } else {
      out << "=" << answerText(errorAnswer(Json(), "worker: unknown tag")) << '\n';
    }
    out.flush();
    if (!out) return 1;
  }
  return 0;
}

}  // namespace crux::cli
