/// @file peer_worker.cpp  A peer backend in a worker process (see peer_worker.hpp).

#include "cli/peer_worker.hpp"

#include <crux/error.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <istream>
#include <ostream>
#include <stdexcept>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace crux::cli {
namespace {

using Clock = std::chrono::steady_clock;

/// How long a new worker may take to say "ready".
constexpr std::chrono::duration<double> kStartupLimit{60.0};

/// "SIGABRT", "SIGSEGV", ... (glibc's abbreviation), or "signal N".
std::string signalText(int sig) {
  const char* abbrev = sigabbrev_np(sig);
  return abbrev ? std::string("SIG") + abbrev : "signal " + std::to_string(sig);
}

/// The last non-empty line of the worker's standard error (the peer's assertion message), at
/// most 300 characters; the file is emptied for the next worker.
std::string lastErrorLine(int fd) {
  std::string text;
  const off_t size = lseek(fd, 0, SEEK_END);
  const off_t from = std::max<off_t>(0, size - 4096);
  text.resize(std::size_t(size - from));
  if (!text.empty() && pread(fd, text.data(), text.size(), from) != ssize_t(text.size())) text.clear();
  if (ftruncate(fd, 0) != 0) text.clear();
  lseek(fd, 0, SEEK_SET);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
  const auto start = text.rfind('\n');
  if (start != std::string::npos) text.erase(0, start + 1);
  if (text.size() > 300) text = text.substr(0, 297) + "...";
  return text;
}

std::string secondsText(double s) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", s);
  return buffer;
}

}  // namespace

PeerWorker::PeerWorker(PeerWorkerOptions options) : options_(std::move(options)) {
  if (!(options_.timeoutSeconds > 0) || !(options_.stateTimeoutSeconds > 0)) throw InvalidInput("timeout: must be positive");
  start();
}

PeerWorker::~PeerWorker() {
  stop();
  if (stderrFile_ >= 0) close(stderrFile_);
}

void PeerWorker::start() {
  if (stderrFile_ < 0) {
    char name[] = "/tmp/crux-worker-stderr-XXXXXX";
    stderrFile_ = mkostemp(name, O_CLOEXEC);
    if (stderrFile_ < 0) throw std::runtime_error(std::string("cannot create a temporary file: ") + std::strerror(errno));
    unlink(name);
  }
  int fds[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
    throw std::runtime_error(std::string("socketpair failed: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 0);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_adddup2(&actions, stderrFile_, 2);
  const std::string backend(backendName(options_.backend));
  std::vector<std::string> args = {options_.executable, "batch", "--backend", backend, "--worker"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, options_.executable.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (err != 0) {
    close(fds[0]);
    throw std::runtime_error("cannot start the " + backend + " worker \"" + options_.executable + "\": " +
                             std::strerror(err));
  }
  pid_ = pid;
  socket_ = fds[0];
  fcntl(socket_, F_SETFL, fcntl(socket_, F_GETFL) | O_NONBLOCK);
  pending_.clear();
  ready_ = false;
  selected_ = -1;
  live_.clear();
}

void PeerWorker::stop() {
  if (socket_ >= 0) {
    shutdown(socket_, SHUT_WR);  // end of input: the worker leaves its loop and exits
    pollfd p{socket_, POLLIN, 0};
    const auto deadline = Clock::now() + std::chrono::milliseconds(500);
    char buffer[256];
    while (Clock::now() < deadline && poll(&p, 1, 50) >= 0) {
      const ssize_t n = recv(socket_, buffer, sizeof buffer, 0);
      if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) break;
    }
  }
  if (pid_ > 0) reap(false);
}

std::string PeerWorker::reap(bool timedOut, double limitSeconds) {
  if (socket_ >= 0) close(socket_);
  socket_ = -1;
  if (pid_ <= 0) return "no worker";
  int status = 0;
  bool reaped = false;
  if (!timedOut) {
    // the socket closes while the process is still exiting: give it 2 s to end by itself, so
    // that its own end (a signal, an exit status) is what gets reported
    const auto deadline = Clock::now() + std::chrono::seconds(2);
    while (!reaped && Clock::now() < deadline) {
      const pid_t done = waitpid(pid_, &status, WNOHANG);
      reaped = done == pid_ || (done < 0 && errno != EINTR);
      if (!reaped) usleep(1000);
    }
  }
  if (!reaped) {
    kill(pid_, SIGKILL);  // stopped by its pid
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
  }
  pid_ = 0;
  const std::string detail = stderrFile_ >= 0 ? lastErrorLine(stderrFile_) : std::string();
  std::string what;
  if (timedOut)
    what = "timeout (no answer within " + secondsText(limitSeconds) + " s; the worker was killed)";
  else if (WIFSIGNALED(status))
    what = signalText(WTERMSIG(status));
  else if (WIFEXITED(status))
    what = "the worker exited with status " + std::to_string(WEXITSTATUS(status));
  else
    what = "the worker ended";
  if (!detail.empty() && !timedOut) what += " (" + detail + ")";
  return what;
}

PeerWorker::Exchange PeerWorker::exchange(const std::vector<std::string>& framed, const std::vector<double>& limits) {
  Exchange result;
  if (pid_ <= 0) {
    try {
      start();
    } catch (const std::exception& e) {
      result.failure = std::string("cannot restart the worker: ") + e.what();
      return result;
    }
    ++restarts_;
  }
  std::string out;
  for (const std::string& line : framed) (out += line) += '\n';
  std::size_t written = 0;
  // the time limit of the reply awaited next
  const auto limit = [&] {
    const std::size_t i = std::min(result.replies.size(), limits.size() - 1);
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(limits[i]));
  };
  // a new worker first says "ready" (loading the libraries takes a while, longer under
  // sanitizers): the time limit per line starts after that
  auto deadline = Clock::now() + (ready_ ? limit() : std::chrono::duration_cast<Clock::duration>(kStartupLimit));
  char buffer[65536];
  while (result.replies.size() < framed.size()) {
    // complete replies already read
    for (std::size_t eol; result.replies.size() < framed.size() && (eol = pending_.find('\n')) != std::string::npos;) {
      std::string reply = pending_.substr(0, eol);
      pending_.erase(0, eol + 1);
      if (!ready_) {
        if (reply != "ready") {
          reap(false);
          result.failure = "the worker did not start (it wrote \"" + reply.substr(0, 100) + "\")";
          return result;
        }
        ready_ = true;
        deadline = Clock::now() + limit();
        continue;
      }
      result.replies.push_back(std::move(reply));
      deadline = Clock::now() + limit();  // the next line's time starts now
    }
    if (result.replies.size() == framed.size()) break;
    const bool sending = ready_ && written < out.size();
    pollfd p{socket_, short(POLLIN | (sending ? POLLOUT : 0)), 0};
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    const int ready = left > 0 ? poll(&p, 1, int(std::min<long long>(left + 1, 1 << 30))) : 0;
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) {
      const bool starting = !ready_;
      const double seconds = limits[std::min(result.replies.size(), limits.size() - 1)];
      result.failure = reap(true, seconds);
      if (starting)
        result.failure = "the worker did not start within " + secondsText(kStartupLimit.count()) + " s (it was killed)";
      return result;
    }
    if (ready < 0) {
      result.failure = reap(false);
      return result;
    }
    if ((p.revents & POLLOUT) && sending) {
      const ssize_t n = send(socket_, out.data() + written, out.size() - written, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n > 0) {
        written += std::size_t(n);
        deadline = Clock::now() + limit();  // a long line's time starts when it has been sent
      } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
        result.failure = reap(false);
        return result;
      }
    }
    if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
      const ssize_t n = recv(socket_, buffer, sizeof buffer, MSG_DONTWAIT);
      if (n > 0) {
        pending_.append(buffer, std::size_t(n));
      } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
        result.failure = reap(false);  // the worker is gone
        return result;
      }
    }
  }
  return result;
}

std::vector<std::string> PeerWorker::answer(const std::vector<std::string>& lines, int slot, bool reset,
                                            std::size_t setupLines) {
  std::vector<std::string> answers;
  answers.reserve(lines.size());
  if (reset) log_[slot].clear();
  bool resetNow = reset;
  while (answers.size() < lines.size()) {
    // one exchange: select the slot (a fresh one after a reset or in a new worker, followed by
    // the replay of its log), then the lines not answered yet
    std::vector<std::string> framed;
    std::vector<double> limits;  // per reply: state lines (replayed, setup) get the state limit
    const bool live = pid_ > 0 && live_.count(slot) > 0;
    std::size_t replayed = 0;
    if (!live || resetNow) {
      framed.push_back("r" + std::to_string(slot));
      for (const std::string& line : log_[slot]) framed.push_back("q" + line);
      replayed = log_[slot].size();
    } else if (selected_ != slot) {
      framed.push_back("s" + std::to_string(slot));
    }
    const std::size_t prefix = framed.size();
    limits.assign(prefix, options_.stateTimeoutSeconds);
    for (std::size_t i = answers.size(); i < lines.size(); ++i) {
      framed.push_back("q" + lines[i]);
      limits.push_back(i < setupLines ? options_.stateTimeoutSeconds : options_.timeoutSeconds);
    }
    const Exchange e = exchange(framed, limits);
    resetNow = false;
    if (e.replies.size() < prefix) {
      // the slot's state could not be restored: the line gets the failure, and the replayed line
      // it failed on is dropped from the log, so that the next attempt does not fail the same way
      const std::size_t failed = e.replies.size();  // index in `framed`
      if (failed >= 1 && failed - 1 < replayed) log_[slot].erase(log_[slot].begin() + std::ptrdiff_t(failed - 1));
      answers.push_back(failureAnswer(lines[answers.size()], options_.backend, e.failure + " (restoring the state)"));
      continue;
    }
    selected_ = slot;
    live_[slot] = true;
    for (std::size_t k = prefix; k < e.replies.size(); ++k) {
      const std::string& reply = e.replies[k];
      if (!reply.empty() && reply[0] == '+') log_[slot].push_back(lines[answers.size()]);
      answers.push_back(reply.empty() ? std::string() : reply.substr(1));
    }
    if (!e.failure.empty()) answers.push_back(failureAnswer(lines[answers.size()], options_.backend, e.failure));
  }
  return answers;
}

}  // namespace crux::cli
