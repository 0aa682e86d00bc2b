// Tests of apps/cli/peer_worker.cpp: a peer backend answered in a worker process that is
// restarted after a crash, an exit or a time-out, with the lost state replayed. The failure kinds
// come from tests/apps/fault_worker.sh (a worker that fails on demand); the real worker is the
// `crux` executable built next to this test.

#include "batch_test_util.hpp"
#include "cli/peer_worker.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace crux::cli {
namespace {

using test::errorOf;

const std::string kFaultWorker = std::string(CRUX_SOURCE_DIR) + "/tests/apps/fault_worker.sh";

Answer parsed(const std::string& text) {
  Answer a = Answer::parse(text, nullptr, false);
  EXPECT_TRUE(a.is_object()) << text;
  return a;
}

PeerWorkerOptions faultWorker(double timeout = 10) { return {kFaultWorker, Backend::Fcl, timeout}; }

bool processExists(pid_t pid) { return kill(pid, 0) == 0 || errno != ESRCH; }

TEST(PeerWorker, AnAbortCostsItsLineOnlyAndTheStateIsReplayed) {
  PeerWorker worker(faultWorker());
  const std::vector<std::string> lines = {R"({"op":"mesh","name":"STATE"})", R"({"op":"distance"})",
                                          R"({"id":"x","op":"distance","note":"ABORT"})", R"({"op":"distance"})"};
  const std::vector<std::string> answers = worker.answer(lines);
  ASSERT_EQ(answers.size(), 4u);
  EXPECT_EQ(parsed(answers[0])["n"], 1);
  EXPECT_EQ(parsed(answers[1])["n"], 2);
  const Answer failed = parsed(answers[2]);
  EXPECT_EQ(failed["id"], "x");
  EXPECT_EQ(failed["op"], "distance");
  EXPECT_EQ(errorOf(failed).rfind("fcl failed on distance: SIGABRT", 0), 0u) << errorOf(failed);
  // the peer's last words (an assertion message on stderr) are quoted
  EXPECT_NE(errorOf(failed).find("isOutsidePolytopeFace"), std::string::npos) << errorOf(failed);
  // a new worker: the state line was replayed into it before the last line (its second q line)
  EXPECT_EQ(parsed(answers[3])["n"], 2);
  EXPECT_EQ(worker.restarts(), 1);
}

TEST(PeerWorker, EveryFailureKindIsNamedAndTheNextLineAnswered) {
  PeerWorker worker(faultWorker());
  struct Kind {
    const char* trigger;
    const char* error;
  };
  for (const Kind k : {Kind{"SEGV", "bullet failed on mesh_sphere: SIGSEGV"},
                       Kind{"EXIT", "bullet failed on mesh_sphere: the worker exited with status 3"}}) {
    PeerWorker bullet({kFaultWorker, Backend::Bullet, 10});
    const std::string bad = std::string(R"({"op":"mesh_sphere","x":")") + k.trigger + "\"}";
    const auto answers = bullet.answer({bad, R"({"op":"mesh_sphere"})"});
    ASSERT_EQ(answers.size(), 2u);
    EXPECT_EQ(errorOf(parsed(answers[0])).rfind(k.error, 0), 0u) << errorOf(parsed(answers[0]));
    EXPECT_EQ(parsed(answers[1])["n"], 1);
  }
  // a line that is not a request still gets an answer naming the backend
  const auto answers = worker.answer({"ABORT, not JSON"});
  EXPECT_EQ(errorOf(parsed(answers[0])).rfind("fcl failed: SIGABRT", 0), 0u) << answers[0];
}

TEST(PeerWorker, AHangIsKilledAtTheTimeLimit) {
  PeerWorker worker(faultWorker(0.3));
  const pid_t first = worker.pid();
  const auto start = std::chrono::steady_clock::now();
  const auto answers = worker.answer({R"({"op":"distance","x":"HANG"})", R"({"op":"distance"})"});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(answers.size(), 2u);
  EXPECT_EQ(errorOf(parsed(answers[0])).rfind("fcl failed on distance: timeout", 0), 0u) << answers[0];
  EXPECT_EQ(parsed(answers[1])["n"], 1);
  EXPECT_LT(seconds, 5.0);
  EXPECT_FALSE(processExists(first));  // killed by its pid and reaped
}

TEST(PeerWorker, SetupLinesHaveTheStateTimeLimit) {
  // a query may take 10 s here, a setup line (or a replayed state line) 0.3 s
  PeerWorker worker({kFaultWorker, Backend::Fcl, 10, 0.3});
  const auto start = std::chrono::steady_clock::now();
  const auto answers = worker.answer({R"({"op":"load_mesh","x":"HANG"})", R"({"op":"distance"})"}, 0, true, 1);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  ASSERT_EQ(answers.size(), 2u);
  EXPECT_EQ(errorOf(parsed(answers[0])).rfind("fcl failed on load_mesh: timeout (no answer within 0.3 s", 0), 0u)
      << answers[0];
  EXPECT_EQ(parsed(answers[1])["n"], 1);
}

TEST(PeerWorker, SlotsKeepTheirOwnStateAndAResetDropsIt) {
  const std::string log = testing::TempDir() + "/peer_worker_slots.log";
  std::remove(log.c_str());
  setenv("FAULT_WORKER_LOG", log.c_str(), 1);
  PeerWorker worker(faultWorker());
  worker.answer({R"({"op":"mesh","name":"STATE-1"})"}, 1, true);
  worker.answer({R"({"op":"mesh","name":"STATE-2"})"}, 2, true);
  worker.answer({R"({"op":"x","y":"ABORT"})"}, 0, true);  // the worker dies
  worker.answer({R"({"op":"distance","q":"after"})"}, 1);   // slot 1 is replayed, not slot 2
  worker.answer({R"({"op":"distance","q":"fresh"})"}, 2, true);  // reset: nothing replayed
  unsetenv("FAULT_WORKER_LOG");
  std::ifstream in(log);
  std::vector<std::string> seen;
  for (std::string line; std::getline(in, line);) seen.push_back(line);
  const std::vector<std::string> want = {R"(q{"op":"mesh","name":"STATE-1"})", R"(q{"op":"mesh","name":"STATE-2"})",
                                         R"(q{"op":"x","y":"ABORT"})",         R"(q{"op":"mesh","name":"STATE-1"})",
                                         R"(q{"op":"distance","q":"after"})",  R"(q{"op":"distance","q":"fresh"})"};
  EXPECT_EQ(seen, want);
}

TEST(PeerWorker, NoProcessIsLeftBehind) {
  pid_t pid = 0;
  {
    PeerWorker worker(faultWorker());
    pid = worker.pid();
    EXPECT_GT(pid, 0);
    EXPECT_TRUE(processExists(pid));
  }
  EXPECT_FALSE(processExists(pid));
}

TEST(PeerWorker, AMissingExecutableIsAnError) {
  EXPECT_THROW(PeerWorker({"/nonexistent/crux", Backend::Fcl, 1}), std::runtime_error);
}

TEST(PeerWorker, TheCruxWorkerAnswersAsTheBackendDoesInProcess) {
  for (const Backend backend : {Backend::Fcl, Backend::Bullet}) {
    BatchOptions options;
    options.backend = backend;
    try {
      BatchState probe(options);
    } catch (const InvalidInput&) {
      continue;  // not built
    }
    const std::vector<std::string> lines = {
        R"({"id":"m","op":"mesh","name":"t","vertices":[[0,0,0],[1,0,0],[0,1,0],[0,0,1]],"triangles":[[0,1,2],[0,1,3],[0,2,3],[1,2,3]]})",
        R"({"id":"s","op":"mesh_sphere","mesh":"t","sphere":{"center":[0.2,0.2,0.2],"radius":0.5}})",
        R"({"id":"a","op":"triangle_sphere","triangle":[[0,0,0],[1,0,0],[0,1,0]],"sphere":{"center":[0.2,0.2,0.1],"radius":0.5}})",
        R"({"id":"bad","op":"mesh_sphere","mesh":"nope","sphere":{"center":[0,0,0],"radius":1}})",
        "not json",
        R"({"id":"r","op":"ray_triangle","triangle":[[0,0,0],[1,0,0],[0,1,0]],"ray":{"origin":[0.2,0.2,1],"dir":[0,0,-1]}})"};
    PeerWorker worker({test::cruxExecutable(), backend, 30});
    const std::vector<std::string> answers = worker.answer(lines);
    BatchState state(options);
    ASSERT_EQ(answers.size(), lines.size());
    for (std::size_t i = 0; i < lines.size(); ++i) {
      std::ostringstream want;
      writeAnswer(want, answerLine(lines[i], state));
      EXPECT_EQ(answers[i] + "\n", want.str()) << lines[i];
    }
  }
}

}  // namespace
}  // namespace crux::cli
