#pragma once
/// @file peer_worker.hpp  A peer backend (fcl, bullet) answered in a worker process, so that a
/// peer library that aborts, crashes or loops on one query costs that query only (docs/batch.md
/// "Isolation").
///
/// The worker is the `crux` executable itself, started with posix_spawn as `crux batch
/// --backend B --worker` and spoken to through a socket pair (its standard input and output).
/// One worker answers every line, so the cost per line is a round trip through the socket, not a
/// process. When the worker dies (a signal, an exit) or gives no answer within the time limit (it
/// is then killed), the line gets the error answer "<backend> failed on <op>: <what happened>",
/// a new worker is started, and the state the lost worker held (the successful `mesh`,
/// `load_mesh`, `add_model`, `set_transform`, `set_parent`, `remove_model` lines) is replayed into
/// it before the next line, so later lines are answered as if nothing had happened.
///
/// Worker protocol (private to this file and runWorker): a new worker first writes "ready"
/// (within 60 s; the time limit per line starts after it). Each line to the worker starts with a
/// tag: 'q' + a request line, 'r' + a slot number (select the slot and give it a fresh state) or
/// 's' + a slot number (select it; a slot never seen starts fresh). The worker answers a 'q' line
/// with '+' (the line changed the state: replay it after a restart) or '=' (it did not) followed
/// by the answer line, and the two others with "ok".

#include "cli/batch.hpp"

#include <sys/types.h>

#include <map>
#include <string>
#include <vector>

namespace crux::cli {

/// Options of a worker process.
struct PeerWorkerOptions {
  /// The `crux` executable (it must accept `batch --backend B --worker`).
  std::string executable;
  Backend backend = Backend::Fcl;
  /// Time limit per line, in seconds (> 0).
  double timeoutSeconds = 30;
  /// Time limit of the state lines replayed into a new worker and of the setup lines of answer
  /// (> 0): loading a large mesh into a peer (FCL's OBBRSS tree of a 100k-triangle mesh) takes
  /// seconds, queries should not.
  double stateTimeoutSeconds = 60;
};

/// A worker process answering the batch protocol for one backend, restarted after a failure.
/// Not thread-safe (one caller at a time).
class PeerWorker {
 public:
  explicit PeerWorker(PeerWorkerOptions options);
  ~PeerWorker();
  PeerWorker(const PeerWorker&) = delete;
  PeerWorker& operator=(const PeerWorker&) = delete;

  /// Answers `lines` in order in state slot `slot` (given a fresh state first when `reset`),
  /// returning each answer line (without '\n'). The first `setupLines` lines have the state
  /// time limit, the others the time limit per line. The lines are written to the worker while its
  /// answers are read (pipelined: one round trip for the lot). A line on which the worker fails
  /// gets failureAnswer's text; the following lines go to a new worker holding the replayed
  /// state. Throws std::runtime_error when no worker can be started at all.
  std::vector<std::string> answer(const std::vector<std::string>& lines, int slot = 0, bool reset = false,
                                  std::size_t setupLines = 0);

  /// Workers started after a failure so far.
  int restarts() const { return restarts_; }
  /// The running worker's process id (0 when none runs).
  pid_t pid() const { return pid_; }

 private:
  /// Result of one exchange with the worker.
  struct Exchange {
    std::vector<std::string> replies;  ///< one per line answered before a failure
    std::string failure;               ///< "" when every line was answered
  };
  void start();
  void stop();
  /// Kills the worker (when alive), reaps it and describes how it ended (`limitSeconds`: the
  /// time limit it exceeded, when `timedOut`).
  std::string reap(bool timedOut, double limitSeconds = 0);
  /// Writes the framed lines and reads a reply per line, within limits[i] seconds for reply i
  /// (the last limit for the rest).
  Exchange exchange(const std::vector<std::string>& framed, const std::vector<double>& limits);

  PeerWorkerOptions options_;
  pid_t pid_ = 0;
  int socket_ = -1;     ///< our end of the socket pair
  int stderrFile_ = -1; ///< the worker's standard error (an unlinked temporary file)
  std::string pending_; ///< bytes read past the last complete reply
  bool ready_ = false;  ///< the running worker has said "ready"
  int restarts_ = 0;
  int selected_ = -1;   ///< the slot the worker has selected (-1: none yet)
  /// Successful state-changing lines per slot, in order (replayed after a restart).
  std::map<int, std::vector<std::string>> log_;
  /// Slots the running worker holds (others are replayed when selected).
  std::map<int, bool> live_;
};

}  // namespace crux::cli
