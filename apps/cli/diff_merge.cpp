/// @file diff_merge.cpp  `crux diff merge`: the summary of a campaign from its shards'
/// directories (docs/diff.md "Campaigns").

#include "cli/diff.hpp"

#include <crux/error.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <set>

namespace crux::cli {
namespace {

using J = Answer;

/// Reads a JSON file; null when it is absent; throws InvalidInput when it is malformed.
J readJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) return nullptr;
  J j = J::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw InvalidInput(path + ": not a JSON object");
  return j;
}

using Counts = std::map<std::string, std::map<std::string, std::uint64_t>>;

Counts readCounts(const J& j, const char* field) {
  Counts out;
  if (!j.contains(field)) return out;
  for (const auto& [outer, inner] : j[field].items())
    for (const auto& [key, n] : inner.items()) out[outer][key] = n.get<std::uint64_t>();
  return out;
}

void addCounts(Counts& into, const Counts& from) {
  for (const auto& [outer, inner] : from)
    for (const auto& [key, n] : inner) into[outer][key] += n;
}

std::string range(std::uint64_t first, std::uint64_t end) {
  return std::to_string(first) + ".." + std::to_string(end - 1);
}

}  // namespace

DiffSummary DiffSummary::fromJson(const Answer& j) {
  DiffSummary s;
  try {
    s.seed = j.at("seed").get<std::uint64_t>();
    s.firstCase = j.at("first_case").get<std::uint64_t>();
    s.requestedCases = j.at("requested_cases").get<std::uint64_t>();
    s.families = j.at("families").get<std::vector<std::string>>();
    s.ops = j.at("ops").get<std::vector<std::string>>();
    s.backends = j.at("backends").get<std::vector<std::string>>();
    s.shrinkPerKind = j.at("shrink_per_kind").get<int>();
    s.cases = j.at("cases").get<std::uint64_t>();
    s.seconds = j.at("seconds").get<double>();
    for (const auto& [op, perBackend] : j.at("table").items())
      for (const auto& [backend, counts] : perBackend.items())
        for (const auto& [verdict, n] : counts.items()) s.table[op][backend][verdict] = n.get<std::uint64_t>();
    s.peerCauses = readCounts(j, "peer_causes");
    s.toleranceCauses = readCounts(j, "within_tolerance_causes");
    s.peerFailures = readCounts(j, "peer_failures");
    s.cruxWrong = j.at("crux_wrong").get<std::uint64_t>();
    for (const auto& f : j.at("findings")) s.findings.push_back(f);
    s.exampleErrors = j.at("error_examples").get<std::map<std::string, std::string>>();
    s.exampleErrorCases = j.at("error_example_cases").get<std::map<std::string, std::uint64_t>>();
  } catch (const nlohmann::json::exception& e) {
    throw InvalidInput(std::string("summary: not a crux diff summary (") + e.what() + ")");
  }
  return s;
}

Answer MergedCampaign::toJson() const {
  J j = summary.toJson();
  J shardList = J::array();
  for (const ShardStatus& s : shards) {
    J entry = J{{"dir", s.dir}, {"status", s.status}, {"first_case", s.firstCase}, {"requested_cases", s.requestedCases}};
    if (s.status == "merged") {
      entry["cases"] = s.cases;
      entry["seconds"] = s.seconds;
      entry["cases_per_second"] = s.seconds > 0 ? double(s.cases) / s.seconds : 0.0;
    }
    shardList.push_back(entry);
  }
  j["shards"] = shardList;
  j["missing_cases"] = missingRanges;
  return j;
}

bool MergedCampaign::complete() const {
  for (const ShardStatus& s : shards)
    if (s.status == "missing" || s.status == "failed") return false;
  return missingRanges.empty();
}

void MergedCampaign::print(std::ostream& out) const {
  summary.print(out);
  std::size_t merged = 0;
  for (const ShardStatus& s : shards) merged += s.status == "merged";
  out << "shards merged: " << merged << " of " << shards.size() << '\n';
  for (const ShardStatus& s : shards) {
    if (s.status == "missing") out << "shard missing: " << s.dir << " (no summary.json, no started.json)\n";
    if (s.status == "failed")
      out << "shard failed: " << s.dir << " (cases " << range(s.firstCase, s.firstCase + s.requestedCases)
          << " started, no summary: cancelled, crashed or still running)\n";
    if (s.status == "duplicate") out << "shard skipped: " << s.dir << " (the same cases as a shard merged before)\n";
  }
  for (const std::string& r : missingRanges) out << "cases not answered by any merged shard: " << r << '\n';
}

int runMergeCommand(const std::vector<std::string>& dirs, const std::string& jsonFile, const std::string& outDir,
                    bool quiet, std::ostream& out) {
  const MergedCampaign campaign = mergeShards(dirs);
  if (!quiet) campaign.print(out);
  if (!jsonFile.empty()) writeJsonFile(jsonFile, campaign.toJson());
  if (!outDir.empty()) {
    std::filesystem::create_directories(outDir);
    std::set<std::string> kept;
    for (const J& f : campaign.summary.findings) kept.insert(f.value("name", ""));
    for (const ShardStatus& s : campaign.shards) {
      if (s.status != "merged") continue;
      for (const std::string& name : kept)
        for (const char* ext : {".jsonl", ".json"}) {
          const std::filesystem::path from = std::filesystem::path(s.dir) / "findings" / (name + ext);
          std::error_code ec;
          if (std::filesystem::exists(from, ec))
            std::filesystem::copy_file(from, std::filesystem::path(outDir) / (name + ext),
                                       std::filesystem::copy_options::overwrite_existing, ec);
        }
    }
  }
  if (campaign.summary.cruxWrong > 0) return 1;
  return campaign.complete() ? 0 : 3;
}

MergedCampaign mergeShards(const std::vector<std::string>& dirs) {
  if (dirs.empty()) throw InvalidInput("merge: no shard directory given");
  MergedCampaign campaign;
  DiffSummary& total = campaign.summary;
  std::vector<DiffSummary> merged;
  std::set<std::pair<std::uint64_t, std::uint64_t>> ranges;  // merged [first, end)
  std::vector<std::pair<std::uint64_t, std::uint64_t>> failedRanges;
  for (const std::string& dir : dirs) {
    ShardStatus status;
    status.dir = dir;
    const J summary = readJson(dir + "/summary.json");
    if (summary.is_null()) {
      const J started = readJson(dir + "/started.json");
      status.status = started.is_null() ? "missing" : "failed";
      if (!started.is_null()) {
        status.firstCase = started.value("first_case", std::uint64_t(0));
        status.requestedCases = started.value("requested_cases", std::uint64_t(0));
        failedRanges.emplace_back(status.firstCase, status.firstCase + status.requestedCases);
      }
      campaign.shards.push_back(status);
      continue;
    }
    DiffSummary shard;
    try {
      shard = DiffSummary::fromJson(summary);
    } catch (const InvalidInput& e) {
      throw InvalidInput(dir + "/summary.json: " + e.what());
    }
    if (shard.requestedCases == 0)
      throw InvalidInput(dir + ": a --seconds run has no case range; shards are runs of --first-case and --cases");
    status.firstCase = shard.firstCase;
    status.requestedCases = shard.requestedCases;
    status.seconds = shard.seconds;
    status.cases = shard.cases;
    if (!merged.empty()) {
      const DiffSummary& first = merged.front();
      const auto differs = [&](const char* what) {
        return InvalidInput(dir + ": " + what + " differ from those of " + campaign.shards.front().dir +
                            " (shards of one campaign run the same options)");
      };
      if (shard.seed != first.seed) throw differs("the seed");
      if (shard.families != first.families) throw differs("the families");
      if (shard.ops != first.ops) throw differs("the ops");
      if (shard.backends != first.backends) throw differs("the backends");
      if (shard.shrinkPerKind != first.shrinkPerKind) throw differs("the shrink limits");
    }
    const std::pair<std::uint64_t, std::uint64_t> r{shard.firstCase, shard.firstCase + shard.requestedCases};
    if (ranges.count(r)) {
      status.status = "duplicate";
      campaign.shards.push_back(status);
      continue;
    }
    for (const auto& [a, b] : ranges)
      if (r.first < b && a < r.second)
        throw InvalidInput(dir + ": cases " + range(r.first, r.second) + " overlap another shard's " + range(a, b));
    ranges.insert(r);
    status.status = "merged";
    campaign.shards.push_back(status);
    merged.push_back(std::move(shard));
  }
  // the ranges no merged shard answered: gaps between merged ranges, and failed shards' ranges
  std::uint64_t end = ranges.empty() ? 0 : ranges.begin()->first;
  for (const auto& [a, b] : failedRanges) end = std::min(end, a);
  std::set<std::pair<std::uint64_t, std::uint64_t>> holes;
  for (const auto& [a, b] : ranges) {
    if (a > end) holes.emplace(end, a);
    end = std::max(end, b);
  }
  for (const auto& [a, b] : failedRanges)
    if (b > end) holes.emplace(std::max(a, end), b);
  for (const auto& [a, b] : holes)
    if (b > a) campaign.missingRanges.push_back(range(a, b));
  if (merged.empty()) return campaign;

  // sums, in case order
  std::sort(merged.begin(), merged.end(), [](const DiffSummary& a, const DiffSummary& b) { return a.firstCase < b.firstCase; });
  const DiffSummary& first = merged.front();
  total.seed = first.seed;
  total.families = first.families;
  total.ops = first.ops;
  total.backends = first.backends;
  total.shrinkPerKind = first.shrinkPerKind;
  total.firstCase = first.firstCase;
  std::vector<J> findings;
  for (const DiffSummary& s : merged) {
    total.requestedCases += s.requestedCases;
    total.cases += s.cases;
    total.seconds += s.seconds;
    total.cruxWrong += s.cruxWrong;
    for (const auto& [op, perBackend] : s.table)
      for (const auto& [backend, counts] : perBackend)
        for (const auto& [verdict, n] : counts) total.table[op][backend][verdict] += n;
    addCounts(total.peerCauses, s.peerCauses);
    addCounts(total.toleranceCauses, s.toleranceCauses);
    addCounts(total.peerFailures, s.peerFailures);
    for (const auto& [where, text] : s.exampleErrors) {
      const auto index = s.exampleErrorCases.find(where);
      const std::uint64_t at = index == s.exampleErrorCases.end() ? ~std::uint64_t(0) : index->second;
      const auto known = total.exampleErrorCases.find(where);
      if (total.exampleErrors.count(where) && known != total.exampleErrorCases.end() && known->second <= at) continue;
      total.exampleErrors[where] = text;
      total.exampleErrorCases[where] = at;
    }
    findings.insert(findings.end(), s.findings.begin(), s.findings.end());
  }
  // findings: case order (a case's findings keep their order), no name twice, and per kind the
  // first shrinkPerKind (a serial run shrinks only those)
  std::stable_sort(findings.begin(), findings.end(), [](const J& a, const J& b) {
    return a.value("index", std::uint64_t(0)) < b.value("index", std::uint64_t(0));
  });
  std::set<std::string> names;
  std::map<std::string, int> perKind;
  for (J& f : findings) {
    if (!names.insert(f.value("name", "")).second) continue;
    if (perKind[f.value("kind", "")]++ >= total.shrinkPerKind) continue;
    total.findings.push_back(std::move(f));
  }
  return campaign;
}

}  // namespace crux::cli
