/// @file report_verdict.cpp  The verdict at the top of `crux report` (per peer wins, losses,
/// geometric mean and worst row; crux-wrong count and peer disagreements by cause) and the
/// comparison of two reports (`--compare`). Pure functions of results.json (report.hpp).

#include "cli/report.hpp"
#include "cli/report_figures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace crux::cli {
namespace {

using Json = nlohmann::json;
using namespace report;

/// The cross-validation part of the verdict: what crux diff and the sanity suite found.
Json correctness(const Json& results) {
  Json c = Json::object();
  const Json cross = results.value("cross_validation", Json::object());
  const Json sanity = cross.value("sanity", Json::object());
  c["sanity_available"] = sanity.value("available", false) && sanity.contains("tests");
  c["sanity_tests"] = sanity.value("tests", 0);
  c["sanity_failures"] = sanity.value("failures", 0);
  const Json diff = cross.value("diff", Json::object());
  const Json data = diff.value("data", Json());
  const bool diffOk = diff.value("available", false) && data.is_object();
  c["diff_available"] = diffOk;
  c["diff_reason"] = diffOk ? "" : diff.value("available", false) ? "crux diff wrote no summary" : str(diff, "reason");
  c["diff_cases"] = diffOk ? data.value("cases", 0) : 0;
  c["crux_wrong"] = diffOk ? data.value("crux_wrong", 0) : 0;
  // Per backend: peer_wrong by cause, within tolerance, errors, the ops compared.
  Json backends = Json::object();
  if (diffOk && data.contains("table") && data["table"].is_object())
    for (const auto& [op, perBackend] : data["table"].items())
      for (const auto& [backend, verdicts] : perBackend.items()) {
        Json& b = backends[backend];
        if (b.is_null()) b = {{"answers", 0}, {"agree", 0}, {"within_tolerance", 0}, {"peer_wrong", 0}, {"crux_wrong", 0},
                              {"error", 0}, {"unsupported", 0}, {"no_arbiter", 0}};
        for (const auto& [verdict, n] : verdicts.items()) {
          if (!n.is_number()) continue;
          b["answers"] = b["answers"].get<double>() + n.get<double>();
          b[verdict] = b.value(verdict, 0.0) + n.get<double>();
        }
      }
  if (diffOk)
    for (const char* key : {"peer_causes", "within_tolerance_causes"})
      if (data.contains(key) && data[key].is_object())
        for (const auto& [backend, causes] : data[key].items())
          backends[backend][std::string(key) == "peer_causes" ? "peer_wrong_causes" : "within_tolerance_causes"] = causes;
  c["backends"] = backends;
  return c;
}

}  // namespace

nlohmann::json reportVerdict(const nlohmann::json& results) {
  Json v = Json::object();
  std::vector<std::string> peers;
  const std::vector<HeadRow> rows = headRows(results, &peers);
  Json perf = Json::array();
  for (const std::string& peer : peers) {
    int wins = 0, losses = 0, differ = 0;
    double logSum = 0;
    Json worst, best;
    for (const HeadRow& row : rows) {
      const Entry* e = row.peer(peer);
      if (!e || row.valueUnit != "seconds" || !(row.crux.seconds > 0) || !(e->seconds > 0)) continue;
      if (answersDiffer(e->agreement)) {
        ++differ;  // a peer that answered differently is not timed against crux
        continue;
      }
      const double ratio = e->seconds / row.crux.seconds;
      (ratio > 1 ? wins : losses) += 1;
      logSum += std::log(ratio);
      const Json here = {{"workload", row.workload}, {"title", row.title}, {"input", row.input}, {"ratio", ratio},
                         {"engine", e->label}};
      if (worst.is_null() || ratio < worst["ratio"].get<double>()) worst = here;
      if (best.is_null() || ratio > best["ratio"].get<double>()) best = here;
    }
    if (wins + losses + differ == 0) continue;
    Json p = {{"peer", peer}, {"name", backendName(peer)}, {"workloads", wins + losses}, {"crux_faster", wins},
              {"crux_slower", losses}, {"answers_differ", differ}, {"worst", worst}, {"best", best}};
    p["geomean"] = wins + losses ? Json(std::exp(logSum / (wins + losses))) : Json(nullptr);
    perf.push_back(p);
  }
  v["performance"] = perf;
  v["correctness"] = correctness(results);
  const Json m = results.value("machine", Json::object());
  const Json r = results.value("report", Json::object());
  // Each line joins the parts that are known.
  const auto join = [](const std::vector<std::string>& parts) {
    std::string s;
    for (const std::string& p : parts)
      if (!p.empty()) s += (s.empty() ? "" : ", ") + p;
    return s;
  };
  const double kB = std::atof(str(m, "memory").c_str());  // /proc/meminfo: "8132412 kB"
  v["machine"] = join({str(m, "cpu"), m.contains("hardware_threads") ? std::to_string(m.value("hardware_threads", 0)) + " threads" : "",
                       kB > 0 ? fmt("%.1f GB memory", kB / (1024 * 1024)) : ""});
  v["build"] = join({"crux " + str(m, "crux_version") + (str(m, "crux_real").empty() ? "" : " (Real = " + str(m, "crux_real") + ")"),
                     str(m, "compiler") + (str(m, "build_type").empty() ? "" : " " + str(m, "build_type")) +
                         (str(m, "cxx_flags").empty() ? "" : " [" + str(m, "cxx_flags") + "]")});
  if (str(r, "budget") == "tiny") v["note"] = "Budget tiny: a test of the report itself; its timings mean nothing.";
  v["run"] = join({str(r, "date"), str(r, "budget").empty() ? "" : "budget " + str(r, "budget"),
                   str(r, "bench_clock").empty() ? "" : "bench clock " + str(r, "bench_clock"),
                   r.contains("seconds") ? fmt("%.0f s", num(r, "seconds")) : ""});
  return v;
}

nlohmann::json compareResults(const nlohmann::json& older, const nlohmann::json& newer) {
  const std::vector<HeadRow> oldRows = headRows(older), newRows = headRows(newer);
  // A row's noise in one run: the relative spread of crux's runs plus the peer's (bench_mesh
  // records every run); the noise of a change: old + new. Rows without runs take the median of
  // the measured noises of their report, marked as estimated; none measured: not flagged.
  struct Noise {
    double value;
    bool measured;
  };
  const auto medianNoise = [](const std::vector<HeadRow>& rows) {
    std::vector<double> all;
    for (const HeadRow& r : rows)
      for (const auto& [peer, e] : r.peers) {
        const double n = relativeSpread(r.crux.runs) + relativeSpread(e.runs);
        if (std::isfinite(n)) all.push_back(n);
      }
    if (all.empty()) return std::nan("");
    std::sort(all.begin(), all.end());
    return all[all.size() / 2];
  };
  const double oldMedian = medianNoise(oldRows), newMedian = medianNoise(newRows);
  const auto noiseOf = [](const Entry& crux, const Entry* peer, double fallback) {
    const double n = relativeSpread(crux.runs) + (peer ? relativeSpread(peer->runs) : 0.0);
    return std::isfinite(n) ? Noise{n, true} : Noise{fallback, false};
  };
  Json rows = Json::array();
  int regressions = 0, improvements = 0;
  const auto judge = [&](Json row, double oldValue, double newValue, Noise oldNoise, Noise newNoise, bool higherIsBetter) {
    const double change = newValue / oldValue - 1;
    const double noise = oldNoise.value + newNoise.value;
    row["old"] = oldValue;
    row["new"] = newValue;
    row["change"] = change;
    row["noise"] = std::isfinite(noise) ? Json(noise) : Json(nullptr);
    row["noise_measured"] = oldNoise.measured && newNoise.measured;
    std::string flag;
    if (std::isfinite(noise) && std::abs(change) > noise) {
      const bool better = higherIsBetter ? change > 0 : change < 0;
      flag = better ? "improvement" : "regression";
      (better ? improvements : regressions) += 1;
    }
    row["flag"] = flag;
    rows.push_back(row);
  };
  for (const HeadRow& n : newRows) {
    const auto o = std::find_if(oldRows.begin(), oldRows.end(), [&n](const HeadRow& r) { return r.workload == n.workload; });
    if (o == oldRows.end() || n.valueUnit != o->valueUnit) continue;
    // crux's own figure (time or bytes): lower is better.
    if (o->crux.seconds > 0 && n.crux.seconds > 0)
      judge({{"workload", n.workload}, {"title", n.title}, {"what", "crux " + std::string(n.valueUnit == "bytes" ? "bytes" : "time") + " per " + n.unit},
             {"value_unit", n.valueUnit}, {"peer", "crux"}},
            o->crux.seconds, n.crux.seconds, noiseOf(o->crux, nullptr, oldMedian), noiseOf(n.crux, nullptr, newMedian), false);
    for (const auto& [peer, e] : n.peers) {
      const Entry* oe = o->peer(peer);
      if (!oe || !(oe->seconds > 0) || !(o->crux.seconds > 0) || !(n.crux.seconds > 0)) continue;
      judge({{"workload", n.workload}, {"title", n.title}, {"what", backendName(peer) + " / crux"}, {"value_unit", "ratio"},
             {"peer", peer}},
            oe->seconds / o->crux.seconds, e.seconds / n.crux.seconds, noiseOf(o->crux, oe, oldMedian),
            noiseOf(n.crux, &e, newMedian), true);
    }
  }
  const Json r = older.value("report", Json::object());
  Json c = {{"old_date", str(r, "date")}, {"old_budget", str(r, "budget")}, {"old_bench_clock", str(r, "bench_clock")},
            {"rows", rows}, {"regressions", regressions}, {"improvements", improvements}};
  const Json nr = newer.value("report", Json::object());
  c["same_clock"] = str(r, "bench_clock") == str(nr, "bench_clock");
  c["same_budget"] = str(r, "budget") == str(nr, "budget");
  return c;
}

}  // namespace crux::cli
