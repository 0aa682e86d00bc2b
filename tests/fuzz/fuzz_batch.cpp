/// @file fuzz_batch.cpp  libFuzzer target fuzz_batch: arbitrary lines into the `crux batch`
/// protocol (apps/cli/batch.hpp, /work/shared/contracts/batch-protocol.md).
///
/// The input is split at '\n' into lines; one BatchState lives for the whole input, so
/// definitions (mesh, add_model, ...) made by earlier lines are used by later ones. Each line goes
/// through crux::cli::answerLine and writeAnswer. Checked: no crash, hang or UB; answerLine never
/// throws; every answer is one JSON object written as exactly one line that parses back to an
/// object with the same members.
///
/// `load_mesh` requests are skipped: their path names an arbitrary file (/dev/zero would block
/// the fuzzer, not crux); file contents are fuzzed by fuzz_load_mesh instead.

#include "fuzz_input.hpp"

#include "cli/batch.hpp"

#include <sstream>
#include <string>

namespace crux::fuzz {
namespace {

bool isLoadMesh(const std::string& line) {
  const cli::Json request = cli::Json::parse(line, nullptr, /*allow_exceptions=*/false);
  if (!request.is_object()) return false;
  const auto op = request.find("op");
  return op != request.end() && op->is_string() && op->get<std::string>() == "load_mesh";
}

void answerOne(const std::string& line, cli::BatchState& state) {
  if (isLoadMesh(line)) return;
  const cli::Answer answer = cli::answerLine(line, state);
  if (!answer.is_object()) fail("answer is not an object: " + answer.dump() + " for line " + cli::Json(line).dump());
  std::ostringstream out;
  cli::writeAnswer(out, answer);
  const std::string text = out.str();
  if (text.empty() || text.back() != '\n' || text.find('\n') != text.size() - 1)
    fail("answer is not exactly one line: " + cli::Json(text).dump() + " for line " + cli::Json(line).dump());
  const cli::Json back = cli::Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!back.is_object() || back.size() != answer.size())
    fail("written answer does not parse back to the object: " + text + " for line " + cli::Json(line).dump());
}

}  // namespace

void run(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  cli::BatchState state;
  std::size_t start = 0;
  while (start <= input.size()) {
    std::size_t end = input.find('\n', start);
    if (end == std::string::npos) end = input.size();
    answerOne(input.substr(start, end - start), state);
    start = end + 1;
  }
}

}  // namespace crux::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  crux::fuzz::run(data, size);
  return 0;
}
