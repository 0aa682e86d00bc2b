#include "cli/report.hpp"

#include "cli/batch.hpp"
#include "cli/report_figures.hpp"

#include <crux/config.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <ostream>
#include <sstream>
#include <thread>
#include <utility>

#include <dirent.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

// Baked in by apps/CMakeLists.txt; the fallbacks keep the file compiling elsewhere.
#ifndef CRUX_REPORT_COMPILER
#define CRUX_REPORT_COMPILER "unknown"
#endif
#ifndef CRUX_REPORT_CXX_FLAGS
#define CRUX_REPORT_CXX_FLAGS "unknown"
#endif
#ifndef CRUX_REPORT_SOURCE_DIR
#define CRUX_REPORT_SOURCE_DIR "."
#endif
#ifndef CRUX_REPORT_BUILD_TYPE
#define CRUX_REPORT_BUILD_TYPE "unknown"
#endif

namespace crux::cli {
namespace {

using Json = nlohmann::json;

// ---- files and processes ----------------------------------------------------------------------

bool isExecutable(const std::string& path) { return access(path.c_str(), X_OK) == 0; }

bool makeDirectory(const std::string& path) {
  if (mkdir(path.c_str(), 0755) == 0) return true;
  struct stat st {};
  return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string directoryOfSelf() {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (n <= 0) return ".";
  const std::string path(self, std::size_t(n));
  return path.substr(0, path.rfind('/'));
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  return bool(out);
}

/// A finished subprocess.
struct RunResult {
  int status = -1;  ///< exit status; 128 + signal when killed; -1 when it could not start
  double seconds = 0;
  bool timedOut = false;
};

/// Runs argv[0] (a path) with stdout and stderr appended to `logPath` and stdin from
/// `stdinPath`; waits for it, calling `tick` about twice a second. With a timeout (> 0) the
/// process runs in its own process group, killed as a whole after `timeoutSeconds`; without
/// one it stays in ours, so a Ctrl-C on the terminal stops it with the report.
RunResult runProcess(const std::vector<std::string>& argv, const std::string& logPath,
                     const std::string& stdinPath = "/dev/null", double timeoutSeconds = 0,
                     const std::function<void()>& tick = nullptr) {
  RunResult r;
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, logPath.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, stdinPath.c_str(), O_RDONLY, 0);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  if (timeoutSeconds > 0) {
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attributes, 0);
  }
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&start] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  pid_t pid = 0;
  const int err = posix_spawn(&pid, args[0], &actions, &attributes, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (err != 0) return r;
  int wstatus = 0;
  double lastTick = 0;
  for (;;) {
    const pid_t done = waitpid(pid, &wstatus, WNOHANG);
    if (done == pid || (done < 0 && errno != EINTR)) break;
    if (timeoutSeconds > 0 && elapsed() > timeoutSeconds && !r.timedOut) {
      r.timedOut = true;
      kill(-pid, SIGKILL);
    }
    if (tick && elapsed() - lastTick >= 0.5) {
      lastTick = elapsed();
      tick();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(elapsed() < 1 ? 5 : 100));
  }
  if (r.timedOut) kill(-pid, SIGKILL);  // what the process left behind in its group
  r.seconds = elapsed();
  r.status = WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : 128 + WTERMSIG(wstatus);
  return r;
}

std::string commandLine(const std::vector<std::string>& argv) {
  std::string s;
  for (const std::string& a : argv) s += (s.empty() ? "" : " ") + a;
  return s;
}

/// Parses a JSON file; null when absent or malformed.
Json readJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) return nullptr;
  Json j = Json::parse(in, nullptr, false);
  return j.is_discarded() ? Json(nullptr) : j;
}

// ---- machine description ---------------------------------------------------------------------

std::string cpuinfoField(const std::string& field) {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(field, 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(std::min(line.size(), colon + 2));
    }
  }
  return "";
}

std::string firstWordAfter(const std::string& path, const std::string& prefix) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(prefix, 0) == 0) return line.substr(prefix.size());
  return "";
}

std::string trim(std::string s) {
  const auto b = s.find_first_not_of(" \t\n");
  const auto e = s.find_last_not_of(" \t\n");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

/// Version of an installed Debian package, "" when dpkg does not know it.
std::string debianVersion(const std::string& package, const std::string& logPath) {
  const std::string out = logPath + ".tmp";
  std::remove(out.c_str());
  const RunResult r = runProcess({"/usr/bin/dpkg-query", "-W", "-f=${Version}", package}, out);
  const std::string v = r.status == 0 ? trim(readText(out)) : "";
  std::remove(out.c_str());
  return v;
}

std::string loadAverage() { return trim(readText("/proc/loadavg")); }

Json machineDescription(const std::string& scratch) {
  Json m = Json::object();
  m["cpu"] = cpuinfoField("model name");
  m["hardware_threads"] = std::thread::hardware_concurrency();
  int processors = 0;
  {
    std::ifstream in("/proc/cpuinfo");
    for (std::string line; std::getline(in, line);) processors += line.rfind("processor", 0) == 0;
  }
  m["processors"] = processors;
  m["memory"] = trim(firstWordAfter("/proc/meminfo", "MemTotal:"));
  utsname u{};
  if (uname(&u) == 0) m["os"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
  m["compiler"] = CRUX_REPORT_COMPILER;
  m["cxx_flags"] = trim(CRUX_REPORT_CXX_FLAGS);
  m["build_type"] = CRUX_REPORT_BUILD_TYPE;
  m["crux_version"] = CRUX_VERSION_STRING;
  m["crux_real"] = CRUX_DOUBLE_PRECISION_ENABLED ? "double" : "float";
  Json libs = Json::object();
  libs["eigen (headers compiled in)"] = std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) +
                                        "." + std::to_string(EIGEN_MINOR_VERSION);
  // Installed package versions (the benches add the versions their headers report).
  for (const char* package : {"libfcl-dev", "libbullet-dev", "libembree-dev", "libcgal-dev", "libeigen3-dev",
                              "libtbb-dev", "libccd-dev", "libassimp-dev"}) {
    const std::string v = debianVersion(package, scratch);
    libs[package] = v.empty() ? "not installed (or not a Debian system)" : v;
  }
  m["libraries"] = libs;
  m["load_average_start"] = loadAverage();
  return m;
}

std::string utcNow() {
  const std::time_t t = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

// ---- steps ----------------------------------------------------------------------------------

std::string minutes(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  return buf;
}

/// Shared state of one run: where things go and how progress is shown. Every line goes to
/// raw/progress.log; on a terminal, one status line is redrawn on `progress`: the step, its
/// number, the time it has run, and the time left estimated from the steps' expected durations
/// (the previous run in the same directory when it had the same budget, else typical figures).
struct Context {
  ReportOptions options;
  std::string rawDir;
  std::ostream* progress = nullptr;
  std::ofstream log;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  int failures = 0;
  std::string clock;  ///< "wall" or "cpu", resolved from options.clock
  std::vector<std::pair<std::string, double>> plan;  ///< every step and its expected seconds
  std::size_t step = 0;                               ///< 1-based index in plan of the running step
  double stepStart = 0;

  double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); }
  void say(const std::string& line) {
    log << "crux report [" << std::fixed << std::setprecision(1) << elapsed() << " s] " << line << std::endl;
  }
  /// Starts the step `name` of the plan.
  void begin(const std::string& name) {
    for (std::size_t i = 0; i < plan.size(); ++i)
      if (plan[i].first == name || name.rfind(plan[i].first + "-", 0) == 0) step = i + 1;
    stepStart = elapsed();
    draw();
  }
  void draw() {
    if (!options.progressLine || step == 0) return;
    const double inStep = elapsed() - stepStart;
    double left = std::max(0.0, plan[step - 1].second - inStep);
    for (std::size_t i = step; i < plan.size(); ++i) left += plan[i].second;
    *progress << "\r\033[Kcrux report [" << step << "/" << plan.size() << "] " << plan[step - 1].first << ": " << minutes(inStep)
              << " (total " << minutes(elapsed()) << ", about " << minutes(left) << " left)" << std::flush;
  }
  /// Clears the status line (before a message that must stay, and at the end).
  void clearLine() {
    if (options.progressLine) *progress << "\r\033[K" << std::flush;
  }
  std::string bin(const std::string& name) const { return options.binDir + "/" + name; }
};

Json unavailable(const std::string& reason) { return Json{{"available", false}, {"reason", reason}}; }

/// Runs one step's command, logging to raw/<name>.log; reads raw/<name>.json if `json`.
Json runStep(Context& c, const std::string& name, const std::vector<std::string>& argv, bool json) {
  const std::string log = c.rawDir + "/" + name + ".log";
  const std::string jsonPath = c.rawDir + "/" + name + ".json";
  std::remove(log.c_str());
  std::remove(jsonPath.c_str());
  c.say("running " + commandLine(argv));
  c.begin(name);
  const RunResult r = runProcess(argv, log, "/dev/null", 0, [&c] { c.draw(); });
  Json step = Json::object();
  step["available"] = true;
  step["command"] = commandLine(argv);
  step["exit_status"] = r.status;
  step["seconds"] = r.seconds;
  step["log"] = "raw/" + name + ".log";
  if (json) {
    step["data"] = readJson(jsonPath);
    if (step["data"].is_null()) step["error"] = "no JSON output (" + jsonPath + ")";
  }
  std::ostringstream done;
  done << name << ": exit " << r.status << " after " << std::fixed << std::setprecision(1) << r.seconds << " s";
  c.say(done.str());
  return step;
}

Json sanitySuite(Context& c) {
  const std::string exe = c.bin("test_sanity");
  if (!isExecutable(exe)) return unavailable("test_sanity is not built (CRUX_BUILD_TESTS=OFF or oracle absent)");
  const std::string jsonPath = c.rawDir + "/sanity.json";
  Json step = runStep(c, "sanity", {exe, "--gtest_brief=1", "--gtest_output=json:" + jsonPath}, true);
  const Json& d = step["data"];
  if (d.is_object()) {
    step["tests"] = d.value("tests", 0);
    step["failures"] = d.value("failures", 0);
    Json cases = Json::array();
    for (const Json& suite : d.value("testsuites", Json::array()))
      for (const Json& t : suite.value("testsuite", Json::array()))
        cases.push_back({{"name", suite.value("name", "") + "." + t.value("name", "")},
                         {"passed", !t.contains("failures")}});
    step["cases"] = cases;
  }
  if (step["exit_status"] != 0) ++c.failures;
  return step;
}

/// Attaches to the crux diff findings the report shows (report::kFindingsShownPerCause of each
/// verdict, backend and cause; at most 8 in all on the tiny budget) their case lines
/// (raw/diff-cases) and every built backend's answer to them, through `crux batch` as a user
/// would replay them.
void replayFindings(Context& c, Json& findings) {
  constexpr double kReplaySeconds = 20;  // FCL's GJK may loop forever on some cases (docs/diff.md)
  const int limit = c.options.budget == ReportBudget::Tiny ? 8 : 1000;
  const std::string out = c.rawDir + "/replay.out";
  std::map<std::string, int> shown;
  int replayed = 0;
  for (Json& f : findings) {
    const std::string group = f.value("verdict", "") + "|" + f.value("backend", "") + "|" + f.value("cause", "");
    if (++shown[group] > report::kFindingsShownPerCause || replayed >= limit) continue;
    ++replayed;
    const std::string cases = c.rawDir + "/diff-cases/" + f.value("name", "") + ".jsonl";
    std::ifstream in(cases);
    if (!in) continue;
    Json lines = Json::array();
    for (std::string line; std::getline(in, line);)
      if (!trim(line).empty()) lines.push_back(line);
    f["lines"] = lines;
    Json answers = Json::object();
    for (const auto backend : backendNames()) {
      std::remove(out.c_str());
      const RunResult r = runProcess({c.bin("crux"), "batch", "--backend", std::string(backend)}, out, cases, kReplaySeconds,
                                     [&c] { c.draw(); });
      std::string last;
      std::ifstream answer(out);
      for (std::string line; std::getline(answer, line);)
        if (!trim(line).empty()) last = line;
      if (r.status == 2 && last.find("not built") != std::string::npos) continue;  // a backend not built in
      Json a = Json::parse(last, nullptr, false);
      if (r.timedOut) answers[std::string(backend)] = "no answer within " + std::to_string(int(kReplaySeconds)) + " s (killed)";
      else if (!a.is_discarded() && a.is_object()) answers[std::string(backend)] = a;
      else answers[std::string(backend)] = "exit " + std::to_string(r.status) + (last.empty() ? "" : ": " + last);
    }
    std::remove(out.c_str());
    f["answers"] = answers;
  }
}

/// The files of the known-peer-disagreement corpus (docs/diff.md, "Corpora").
Json corpusFiles() {
  Json files = Json::array();
  const std::string dir = std::string(CRUX_REPORT_SOURCE_DIR) + "/oracle/known-peer-disagreements";
  if (DIR* d = opendir(dir.c_str())) {
    std::vector<std::string> names;
    while (const dirent* e = readdir(d)) {
      const std::string n = e->d_name;
      if (n.size() > 6 && n.compare(n.size() - 6, 6, ".jsonl") == 0) names.push_back(n);
    }
    closedir(d);
    std::sort(names.begin(), names.end());
    for (const std::string& n : names) files.push_back(n);
  }
  return files;
}

/// The cross-validation step from an existing summary (ReportOptions::diffSummary): read, not
/// run; exit status 1 when it counts crux-wrong answers, as crux diff's own.
Json diffFromSummary(Context& c) {
  const std::string& path = c.options.diffSummary;
  Json data = readJson(path);
  if (!data.is_object() || !data.contains("cases") || !data.contains("table"))
    return unavailable("--diff-summary " + path + " is not a crux diff summary (no \"cases\" and \"table\")");
  Json step = Json::object();
  step["available"] = true;
  step["command"] = "read " + path;
  step["summary"] = path;
  step["exit_status"] = data.value("crux_wrong", 0) > 0 ? 1 : 0;
  step["seconds"] = 0.0;
  step["data"] = std::move(data);
  if (step["exit_status"] != 0) ++c.failures;
  c.say("crux diff: read " + path + " (" + std::to_string(step["data"].value("cases", 0)) + " cases)");
  return step;
}

Json diffRun(Context& c) {
  if (!c.options.diffSummary.empty()) return diffFromSummary(c);
  const std::string self = c.bin("crux");
  const std::string probeLog = c.rawDir + "/diff-probe.log";
  std::remove(probeLog.c_str());
  if (!isExecutable(self) || runProcess({self, "diff", "--help"}, probeLog).status != 0)
    return unavailable("not available in this build: `crux diff` is not a subcommand of this crux");
  const char* seconds = c.options.budget == ReportBudget::Tiny ? "2" : c.options.budget == ReportBudget::Quick ? "30" : "300";
  std::vector<std::string> argv = {self, "diff", "--seconds", seconds, "--json", c.rawDir + "/diff.json",
                                   "--out", c.rawDir + "/diff-cases", "--quiet"};
  const std::string meshes = std::string(CRUX_REPORT_SOURCE_DIR) + "/data/meshes";
  if (access(meshes.c_str(), R_OK) == 0) {
    argv.push_back("--meshes");
    argv.push_back(meshes);
  }
  Json step = runStep(c, "diff", argv, true);
  // Exit 1 means crux answered wrong somewhere: a result the report shows, and a failure.
  if (step["exit_status"] != 0) ++c.failures;
  if (step["data"].is_object() && step["data"].contains("findings")) replayFindings(c, step["data"]["findings"]);
  return step;
}

/// The bench steps and their arguments per budget.
struct BenchPlan {
  std::string name;
  std::vector<std::string> tiny, quick, full;
  bool optional = false;  ///< built by other work; absent is not an error
};

std::vector<BenchPlan> benchPlans() {
  return {
      {"bench_mesh",
       {"--quick", "--runs", "1", "--seconds", "0.001"},
       {"--runs", "3", "--seconds", "0.05"},
       {"--runs", "5", "--seconds", "0.2"}},
      {"bench_scene",
       {"--quick", "--sizes", "300", "--runs", "1"},
       {"--quick", "--sizes", "1000,10000", "--runs", "1"},
       {"--sizes", "1000,10000,100000", "--runs", "3"}},
      {"bench_scaling",
       {"--sizes", "1000,4000", "--rays", "200", "--runs", "1", "--seconds", "0.001"},
       {"--quick"},
       {}},
      {"bench_parallel", {"--quick"}, {"--quick"}, {}, true},
      {"bench_contact", {"--quick"}, {"--quick"}, {}, true},
  };
}

Json benches(Context& c) {
  Json all = Json::object();
  for (const BenchPlan& plan : benchPlans()) {
    const std::string exe = c.bin(plan.name);
    if (!isExecutable(exe)) {
      all[plan.name] = unavailable(plan.name + " is not built (CRUX_BUILD_BENCH=OFF, or not in this version)");
      c.say(plan.name + ": not available in this build");
      if (!plan.optional) ++c.failures;
      continue;
    }
    std::vector<std::string> argv = {exe};
    const auto& extra = c.options.budget == ReportBudget::Tiny    ? plan.tiny
                        : c.options.budget == ReportBudget::Quick ? plan.quick
                                                                  : plan.full;
    argv.insert(argv.end(), extra.begin(), extra.end());
    const std::string smallMesh = std::string(CRUX_REPORT_SOURCE_DIR) + "/data/meshes/cow.off";  // 5,804 triangles
    if (plan.name == "bench_mesh" && c.options.budget == ReportBudget::Tiny && access(smallMesh.c_str(), R_OK) == 0) {
      argv.push_back("--mesh");
      argv.push_back(smallMesh);
    }
    if (plan.name == "bench_mesh" || plan.name == "bench_scene" || plan.name == "bench_scaling") {
      argv.push_back("--clock");
      argv.push_back(c.clock);
    }
    argv.push_back("--json");
    argv.push_back(c.rawDir + "/" + plan.name + ".json");
    Json step = runStep(c, plan.name, argv, true);
    if (plan.optional && step["exit_status"] == 0 && step["data"].is_null()) {
      // A bench without --json (its options are ignored): keep its printed tables.
      step.erase("error");
      step["text"] = readText(c.rawDir + "/" + plan.name + ".log");
    } else if (step["exit_status"] != 0 || step["data"].is_null()) {
      ++c.failures;
    }
    all[plan.name] = step;
  }
  return all;
}

}  // namespace

// (documented in report.hpp)
double callgrindCalls(const std::string& file, const std::string& callee) {
  std::ifstream in(file);
  if (!in) return -1;
  std::map<std::string, std::string> names;
  double total = 0;
  bool counting = false;  // within a call record of the callee (its cfn= line seen, not its calls=)
  for (std::string line; std::getline(in, line);) {
    const bool call = line.rfind("cfn=(", 0) == 0;
    if (call || line.rfind("fn=(", 0) == 0) {
      const std::size_t open = line.find('('), close = line.find(')');
      if (close == std::string::npos) continue;
      const std::string id = line.substr(open + 1, close - open - 1);
      if (close + 2 <= line.size()) names[id] = line.substr(close + 2);
      counting = call && names[id].find(callee) != std::string::npos;
      continue;
    }
    if (line.rfind("calls=", 0) == 0) {
      if (counting) total += std::atof(line.c_str() + 6);
      counting = false;
    }
  }
  return total;
}

namespace {

/// Instruction counts (callgrind, inclusive) of each backend's closest-hit ray function on
/// bench_scaling's 10k-triangle torus, 2000 rays, 1 thread. Divided by the number of rays the
/// function cast: its calls of the per-ray query (bench_scaling runs each engine's function on
/// the rays several times: the reference, the agreement pass, the timed runs, the refit check).
Json callgrind(Context& c) {
  const std::string valgrind = "/usr/bin/valgrind";
  const std::string exe = c.bin("bench_scaling");
  if (!isExecutable(valgrind)) return unavailable("valgrind is not installed");
  if (!isExecutable(exe)) return unavailable("bench_scaling is not built");
  Json out = Json::object();
  out["available"] = true;
  out["workload"] = "bench_scaling closest-hit rays, 10k-triangle torus, 2000 rays, 1 thread: instructions (callgrind "
                    "Ir, inclusive) of the backend's ray function over all its passes, divided by passes x rays";
  Json counts = Json::object();
  struct RayFunction {
    std::string backend, pattern, perRay;  // toggle-collect pattern, the per-ray call inside it
  };
  const std::vector<RayFunction> functions = {
      {"crux", "*cruxRays*", "crux::raycastClosest("},
      {"embree", "crux::bench::EmbreePeer::closestHits*", "rtcIntersect1"},
      {"bullet", "crux::bench::BulletPeer::closestHits*", "btCollisionWorld::rayTest("}};
  constexpr double kRays = 2000;
  for (const auto& [backend, pattern, perRay] : functions) {
    const std::string outFile = c.rawDir + "/callgrind." + backend + ".out";
    std::remove(outFile.c_str());
    const Json step = runStep(c, "callgrind-" + backend,
                              {valgrind, "--tool=callgrind", "--callgrind-out-file=" + outFile,
                               "--toggle-collect=" + pattern, exe, "--sizes", "10000", "--rays", "2000", "--runs", "1",
                               "--seconds", "0.0001", "--threads", "1"},
                              false);
    // Summary line: "summary: <Ir>"
    double ir = -1;
    std::ifstream in(outFile);
    for (std::string line; std::getline(in, line);)
      if (line.rfind("summary:", 0) == 0 || line.rfind("totals:", 0) == 0) ir = std::atof(line.substr(line.find(':') + 1).c_str());
    const double rays = callgrindCalls(outFile, perRay);
    if (ir < 0 || !(rays >= kRays) || step["exit_status"] != 0) {
      counts[backend] = nullptr;
      continue;
    }
    counts[backend] = {{"instructions_total", ir}, {"passes", rays / kRays}, {"instructions_per_ray", ir / rays}};
  }
  out["backends"] = counts;
  return out;
}

/// Expected seconds of each step: the previous run in the output directory when it had the same
/// budget, else typical figures of a 2-core machine.
std::vector<std::pair<std::string, double>> stepPlan(const Context& c) {
  const ReportBudget b = c.options.budget;
  const auto typical = [b](double tiny, double quick, double full) {
    return b == ReportBudget::Tiny ? tiny : b == ReportBudget::Quick ? quick : full;
  };
  std::vector<std::pair<std::string, double>> plan;
  if (isExecutable(c.bin("test_sanity"))) plan.emplace_back("sanity", typical(5, 10, 10));
  if (isExecutable(c.bin("crux"))) plan.emplace_back("diff", typical(8, 45, 320));
  const std::map<std::string, std::vector<double>> benchTypical = {{"bench_mesh", {10, 150, 900}},
                                                                   {"bench_scene", {5, 60, 900}},
                                                                   {"bench_scaling", {5, 120, 1200}},
                                                                   {"bench_parallel", {5, 30, 60}},
                                                                   {"bench_contact", {5, 30, 60}}};
  for (const BenchPlan& bench : benchPlans())
    if (isExecutable(c.bin(bench.name))) {
      const auto& t = benchTypical.at(bench.name);
      plan.emplace_back(bench.name, typical(t[0], t[1], t[2]));
    }
  if (c.options.callgrind) plan.emplace_back("callgrind", 300);
  plan.emplace_back("browser", 8);
  const Json previous = readJson(c.options.outDir + "/results.json");
  if (previous.is_object() && previous.value("report", Json::object()).value("budget", "") == budgetName(b))
    for (auto& [name, seconds] : plan) {
      const Json* step = nullptr;
      if (name == "sanity" || name == "diff") step = &previous["cross_validation"][name];
      else if (previous.contains("benches") && previous["benches"].contains(name)) step = &previous["benches"][name];
      if (step && step->is_object() && (*step)["seconds"].is_number()) seconds = (*step)["seconds"].get<double>();
    }
  return plan;
}

/// Every step of a run: machine, cross-validation, benches, callgrind.
Json runSteps(Context& c) {
  const ReportOptions& options = c.options;
  if (options.clock == "auto") {
    const double load = std::atof(loadAverage().c_str());
    c.clock = load > 0.5 * std::max(1u, std::thread::hardware_concurrency()) ? "cpu" : "wall";
  } else {
    c.clock = options.clock == "cpu" ? "cpu" : "wall";
  }
  c.plan = stepPlan(c);
  c.say(std::string("budget ") + budgetName(options.budget) + ", output in " + options.outDir + ", bench clock " + c.clock +
        " (load average " + loadAverage() + ")");
  Json results = Json::object();
  results["report"] = {{"date", utcNow()},          {"budget", budgetName(options.budget)}, {"callgrind", options.callgrind},
                       {"bench_clock", c.clock},    {"bin_dir", c.options.binDir},          {"source_dir", CRUX_REPORT_SOURCE_DIR}};
  c.say("machine description");
  results["machine"] = machineDescription(c.rawDir + "/dpkg");
  c.say("cross-validation: oracle sanity suite");
  Json cross = Json::object();
  cross["sanity"] = sanitySuite(c);
  c.say("cross-validation: crux diff");
  cross["diff"] = diffRun(c);
  if (!cross["diff"].value("available", false)) c.say("crux diff: " + cross["diff"]["reason"].get<std::string>());
  cross["known_peer_disagreements"] = corpusFiles();
  results["cross_validation"] = cross;
  c.say("performance: benches");
  results["benches"] = benches(c);
  if (options.callgrind) {
    c.say("callgrind: instruction counts per backend");
    results["callgrind"] = callgrind(c);
  }
  results["machine"]["load_average_end"] = loadAverage();
  results["report"]["seconds"] = c.elapsed();
  results["report"]["failed_steps"] = c.failures;
  return results;
}

/// Opens DIR/index.html in headless Chromium (apps/cli/report_browser.mjs, driven by Debian's
/// node over the DevTools protocol): console errors, the verdict, the charts and their text
/// measured, and the verdict's screenshot written to DIR/verdict.png. Unavailable without
/// chromium, node or the script (an installed crux without its source tree).
Json browserCheck(Context& c, const std::string& outDir) {
  const std::string chromium = "/usr/bin/chromium", node = "/usr/bin/node";
  const std::string script = std::string(CRUX_REPORT_SOURCE_DIR) + "/apps/cli/report_browser.mjs";
  if (!isExecutable(chromium)) return unavailable("chromium is not installed (scripts/setup installs it)");
  if (!isExecutable(node)) return unavailable("node is not installed (scripts/setup installs it)");
  if (access(script.c_str(), R_OK) != 0) return unavailable(script + " is not there (no source tree)");
  const std::string log = c.rawDir + "/browser.log", json = c.rawDir + "/browser.json", png = outDir + "/verdict.png";
  std::remove(log.c_str());
  std::remove(json.c_str());
  std::remove(png.c_str());
  const std::vector<std::string> argv = {node, script, outDir + "/index.html", "--screenshot", png, "--json", json,
                                         "--chromium", chromium};
  c.say("running " + commandLine(argv));
  c.begin("browser");
  const RunResult r = runProcess(argv, log, "/dev/null", 90, [&c] { c.draw(); });
  Json step = {{"available", true}, {"command", commandLine(argv)}, {"exit_status", r.status}, {"seconds", r.seconds},
               {"log", "raw/browser.log"}};
  step["data"] = readJson(json);
  if (r.timedOut) step["error"] = "no answer within 90 s (killed)";
  if (access(png.c_str(), R_OK) == 0) step["screenshot"] = "verdict.png";
  c.say("browser: exit " + std::to_string(r.status));
  return step;
}

}  // namespace

const char* budgetName(ReportBudget budget) {
  switch (budget) {
    case ReportBudget::Tiny: return "tiny";
    case ReportBudget::Quick: return "quick";
    case ReportBudget::Full: return "full";
  }
  return "?";
}

int runReport(const ReportOptions& options, std::ostream& progress) {
  Context c;
  c.options = options;
  if (c.options.binDir.empty()) c.options.binDir = directoryOfSelf();
  c.progress = &progress;
  c.rawDir = options.outDir + "/raw";
  if (!makeDirectory(options.outDir) || !makeDirectory(c.rawDir)) {
    progress << "crux report: cannot create the output directory " << options.outDir << '\n';
    return 2;
  }
  c.log.open(c.rawDir + "/progress.log", std::ios::app);
  Json older;
  if (!options.compareWith.empty()) {
    older = readJson(options.compareWith);
    if (!older.is_object()) {
      progress << "crux report: cannot read " << options.compareWith << " (--compare: a results.json of an earlier run)\n";
      return 2;
    }
  }
  Json results;
  if (!options.renderFrom.empty()) {
    results = readJson(options.renderFrom);
    if (!results.is_object() || !results.contains("report")) {
      progress << "crux report: cannot read " << options.renderFrom << " (--render: a results.json of crux report)\n";
      return 2;
    }
    c.plan = {{"browser", 8}};
    c.say("re-rendering " + options.renderFrom);
    results["report"]["source_dir"] = CRUX_REPORT_SOURCE_DIR;  // the corpus linked is this checkout's
  } else {
    results = runSteps(c);
  }
  results["series"] = chartSeries(results);
  // Every workload and backend measured, for readers and the test.
  Json workloads = Json::array(), backends = Json::array();
  for (const auto& [id, s] : results["series"].items()) {
    const std::string w = s.value("workload", "");
    if (!w.empty() && std::find(workloads.begin(), workloads.end(), w) == workloads.end()) workloads.push_back(w);
    for (const Json& b : s.value("backends", Json::array()))
      if (std::find(backends.begin(), backends.end(), b) == backends.end()) backends.push_back(b);
  }
  results["workloads"] = workloads;
  results["backends"] = backends;
  results["verdict"] = reportVerdict(results);
  if (older.is_object()) results["comparison"] = compareResults(older, results);
  else results.erase("comparison");
  results.erase("browser");

  c.say("writing results.json, index.html");
  const std::string resultsPath = options.outDir + "/results.json";
  const auto dump = [&results] { return results.dump(1, ' ', false, Json::error_handler_t::replace) + "\n"; };
  bool ok = writeText(resultsPath, dump());
  ok = writeText(options.outDir + "/index.html", renderHtml(results)) && ok;
  if (ok) {
    results["browser"] = browserCheck(c, options.outDir);
    c.say("writing summary.md");
    ok = writeText(options.outDir + "/summary.md", renderSummary(results)) && writeText(resultsPath, dump());
  }
  c.clearLine();
  if (!ok) {
    progress << "crux report: cannot write the outputs in " << options.outDir << '\n';
    return 2;
  }
  const std::string done = "done: " + options.outDir + "/index.html, summary.md, results.json" +
                           (c.failures ? " (" + std::to_string(c.failures) + " step(s) failed: see results.json)" : "");
  c.say(done);
  if (options.progressLine) progress << "crux report: " << done << " in " << minutes(c.elapsed()) << '\n';
  return c.failures ? 1 : 0;
}

}  // namespace crux::cli
