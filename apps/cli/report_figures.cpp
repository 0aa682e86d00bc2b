/// @file report_figures.cpp  The benches' raw JSON read into one shape (report_figures.hpp).

#include "cli/report_figures.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>

namespace crux::cli::report {
namespace {

using Json = nlohmann::json;

/// The backend of an engine name: its leading letters and digits, lower-case ("FCL DynamicAABBTree"
/// and "fcl::distance (...)" are both "fcl").
std::string backendOf(const std::string& engine) {
  std::size_t n = 0;
  while (n < engine.size() && std::isalnum(static_cast<unsigned char>(engine[n]))) ++n;
  return lower(engine.substr(0, n));
}

/// A workload key usable in a series id (ids are separated by spaces in data-series): letters,
/// digits, '_' and '-' kept, every other run of characters becomes one '-'.
std::string keyOf(const std::string& key) {
  std::string out;
  for (const char ch : key) {
    if (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-') out += ch;
    else if (!out.empty() && out.back() != '-') out += '-';
  }
  while (!out.empty() && out.back() == '-') out.pop_back();
  return out;
}

/// bench_mesh's format: {"workloads": [{"key", "title", "unit", "engines": [...]}]}.
void readWorkloadFormat(const std::string& bench, const Json& data, std::vector<WorkloadFigures>& out) {
  const bool cpu = str(data, "reported_clock") == "cpu";
  for (const Json& w : data.value("workloads", Json::array())) {
    WorkloadFigures f;
    f.bench = bench;
    f.key = keyOf(str(w, "key"));
    f.title = str(w, "title");
    f.unit = str(w, "unit");
    if (f.key.empty() || f.unit.empty()) continue;
    if (w.contains("rows")) {
      // bench_parallel: crux alone on 1..N threads; rows [{"threads", "wall_seconds_median"}]
      // per pass over `items` queries.
      f.sizeName = "threads";
      const double items = std::max(1.0, num(w, "items", 1));
      for (const Json& r : w["rows"]) {
        Entry x;
        x.backend = "crux";
        x.label = "crux";
        x.size = num(r, "threads");
        x.seconds = num(r, cpu ? "cpu_seconds_median" : "wall_seconds_median", std::nan("")) / items;
        x.agreement = "";
        f.sweep.push_back(x);
      }
      for (const Entry& x : f.sweep)
        if (x.size == f.sweep.back().size) f.entries.push_back(x);
      if (!f.entries.empty()) out.push_back(f);
      continue;
    }
    const std::string field = std::string(cpu ? "cpu" : "wall") + "_seconds_per_" + f.unit + "_median";
    for (const Json& e : w.value("engines", Json::array())) {
      Entry x;
      x.backend = backendOf(str(e, "name"));
      x.label = str(e, "name") + (str(e, "config").empty() ? "" : " [" + str(e, "config") + "]");
      x.seconds = num(e, field.c_str(), std::nan(""));
      x.agreement = str(e, "agreement");
      const std::string runsField = std::string(cpu ? "cpu" : "wall") + "_seconds_per_" + f.unit + "_runs";
      for (const Json& v : e.value(runsField, Json::array()))
        if (v.is_number()) x.runs.push_back(v.get<double>());
      f.entries.push_back(x);
    }
    if (!f.entries.empty()) out.push_back(f);
  }
  // bench_mesh's "memory": {"<engine>[_<config>]_bytes_per_triangle": value, ...}, crux first.
  const auto memory = data.find("memory");
  if (memory != data.end() && memory->is_object()) {
    WorkloadFigures f;
    f.bench = bench;
    f.key = "memory";
    f.title = "memory per triangle (arrays + BVH)";
    f.unit = "triangle";
    f.valueUnit = "bytes";
    const std::string suffix = "_bytes_per_triangle";
    for (int pass = 0; pass < 2; ++pass)
      for (const auto& [k, v] : memory->items()) {
        if (!v.is_number() || k.size() <= suffix.size() || k.compare(k.size() - suffix.size(), suffix.size(), suffix) != 0)
          continue;
        const std::string name = k.substr(0, k.size() - suffix.size());
        const std::string backend = name.substr(0, name.find('_'));
        if ((pass == 0) != (backend == "crux")) continue;
        Entry x;
        x.backend = backend;
        std::string config = name.size() > backend.size() ? name.substr(backend.size() + 1) : "";
        for (char& ch : config) ch = ch == '_' ? ',' : ch;
        x.label = backend + (config.empty() ? "" : " [" + config + "]");
        x.seconds = v.get<double>();
        f.entries.push_back(x);
      }
    if (!f.entries.empty() && f.entries[0].backend == "crux") out.push_back(f);
  }
}

/// bench_scene's and bench_scaling's format: {"rows": [{"workload", "engine", "config"?,
/// "models"|"triangles", "seconds_per_item", "agreement"}]}.
void readRowFormat(const std::string& bench, const Json& data, std::vector<WorkloadFigures>& out) {
  std::vector<std::string> order;
  std::map<std::string, WorkloadFigures> byWorkload;
  WorkloadFigures memory;  // bench_scaling's build rows carry bytes_per_triangle
  memory.bench = bench;
  memory.key = "memory";
  memory.title = "memory per triangle (arrays + BVH)";
  memory.unit = "triangle";
  memory.valueUnit = "bytes";
  memory.sizeName = "triangles";
  for (const Json& r : data.value("rows", Json::array())) {
    const std::string w = str(r, "workload");
    if (w.empty()) continue;
    if (r.contains("bytes_per_triangle") && r["bytes_per_triangle"].is_number()) {
      Entry x;
      x.backend = backendOf(str(r, "engine"));
      x.label = str(r, "engine") + (str(r, "config").empty() ? "" : " [" + str(r, "config") + "]");
      x.seconds = r["bytes_per_triangle"].get<double>();
      x.size = num(r, "triangles");
      memory.sweep.push_back(x);
    }
    if (!byWorkload.count(w)) {
      order.push_back(w);
      WorkloadFigures& f = byWorkload[w];
      f.bench = bench;
      f.key = slug(w);
      f.title = w;
      f.unit = w == "build" || w == "refit" ? w : w == "update+pairs" ? "frame" : "query";
      f.sizeName = r.contains("models") ? "models" : "triangles";
    }
    WorkloadFigures& f = byWorkload[w];
    Entry x;
    x.backend = backendOf(str(r, "engine"));
    x.label = str(r, "engine") + (str(r, "config").empty() ? "" : " [" + str(r, "config") + "]");
    x.seconds = num(r, "seconds_per_item", std::nan(""));
    x.agreement = str(r, "agreement");
    x.size = num(r, f.sizeName.c_str());
    f.sweep.push_back(x);
  }
  for (const std::string& w : order) {
    WorkloadFigures& f = byWorkload[w];
    double largest = 0;
    for (const Entry& e : f.sweep) largest = std::max(largest, e.size);
    for (const Entry& e : f.sweep)
      if (e.size == largest) f.entries.push_back(e);
    out.push_back(f);
  }
  if (!memory.sweep.empty()) {
    double largest = 0;
    for (const Entry& e : memory.sweep) largest = std::max(largest, e.size);
    for (const Entry& e : memory.sweep)
      if (e.size == largest) memory.entries.push_back(e);
    out.push_back(memory);
  }
}

/// bench_contact's printed tables, read when it wrote no JSON: per pair family ("== name: ...")
/// rows "<query> <ns/query> <peer/crux>", where a row with "-" is a crux reference and the rows
/// after it with a ratio are its peers; "check vs fcl::distance: N of M differ ..." and "check vs
/// libccd EPA depth: N of M differ ..." give the agreement of those peers (the other libccd rows
/// are not checked by the bench, and say so).
void readContactText(const std::string& bench, const std::string& text, std::vector<WorkloadFigures>& out) {
  std::istringstream in(text);
  std::string group, fclAgreement = "not checked", ccdAgreement = "not checked";
  int current = -1;  // index in `out` of the workload of the last crux row
  auto checkVerdict = [](const std::string& line) {
    const auto at = line.find(": ");
    int differ = -1, total = -1;
    if (at == std::string::npos || std::sscanf(line.c_str() + at + 2, "%d of %d", &differ, &total) != 2)
      return std::string("not checked");
    return differ == 0 ? std::string("agree") : "DISAGREE: " + line.substr(at + 2);
  };
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("== ", 0) == 0) {
      const auto colon = line.find(':');
      group = line.substr(3, colon == std::string::npos ? std::string::npos : colon - 3);
      fclAgreement = ccdAgreement = "not checked";
      current = -1;
      continue;
    }
    if (line.rfind("check vs fcl", 0) == 0) fclAgreement = checkVerdict(line);
    if (line.rfind("check vs libccd", 0) == 0) ccdAgreement = checkVerdict(line);
    if (group.empty()) continue;
    std::istringstream fields(line);
    std::vector<std::string> words;
    for (std::string w; fields >> w;) words.push_back(w);
    if (words.size() < 3) continue;
    const std::string ratio = words.back(), nsText = words[words.size() - 2];
    char* end = nullptr;
    const double ns = std::strtod(nsText.c_str(), &end);
    if (end == nsText.c_str() || *end != '\0' || !(ns > 0)) continue;
    std::string label;
    for (std::size_t i = 0; i + 2 < words.size(); ++i) label += (i ? " " : "") + words[i];
    Entry x;
    x.backend = backendOf(label);
    if (x.backend.rfind("fcl", 0) == 0) x.backend = "fcl";
    x.label = label;
    x.seconds = ns * 1e-9;
    if (ratio == "-") {
      if (x.backend != "crux") continue;
      WorkloadFigures f;
      f.bench = bench;
      const std::string what = label.substr(5);  // after "crux "
      f.title = group + ": " + what;
      f.key = slug(group + " " + what.substr(0, what.find(' ')));
      f.unit = "query";
      x.agreement = "ref";
      f.entries.push_back(x);
      out.push_back(f);
      current = int(out.size()) - 1;
    } else if (current >= 0) {
      const bool checkedDepth = label.find("GJKPenetration") != std::string::npos;
      x.agreement = x.backend == "fcl" ? fclAgreement : checkedDepth ? ccdAgreement : "not checked";
      out[std::size_t(current)].entries.push_back(x);
    }
  }
}

}  // namespace

std::string lower(std::string s) {
  for (char& ch : s) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

std::string slug(const std::string& s) {
  std::string out;
  for (const char ch : s) {
    if (std::isalnum(static_cast<unsigned char>(ch))) out += char(std::tolower(static_cast<unsigned char>(ch)));
    else if (!out.empty() && out.back() != '-') out += '-';
  }
  while (!out.empty() && out.back() == '-') out.pop_back();
  return out;
}

std::string str(const Json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::string();
}

double num(const Json& j, const char* key, double fallback) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : fallback;
}

std::vector<WorkloadFigures> figures(const Json& results) {
  std::vector<WorkloadFigures> out;
  const auto benches = results.find("benches");
  if (benches == results.end() || !benches->is_object()) return out;
  // The benches in the report's order (docs/report.md), any others after.
  std::vector<std::string> order = {"bench_mesh", "bench_contact", "bench_scene", "bench_scaling", "bench_parallel"};
  for (const auto& [bench, step] : benches->items())
    if (std::find(order.begin(), order.end(), bench) == order.end()) order.push_back(bench);
  for (const std::string& bench : order) {
    if (!benches->contains(bench)) continue;
    const Json& step = (*benches)[bench];
    const auto data = step.find("data");
    if (data == step.end() || !data->is_object()) {
      if (bench == "bench_contact" && step.contains("text") && step["text"].is_string())
        readContactText(bench, step["text"].get<std::string>(), out);
      continue;
    }
    if (data->contains("workloads")) readWorkloadFormat(bench, *data, out);
    else if (data->contains("rows")) readRowFormat(bench, *data, out);
  }
  return out;
}

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string duration(double seconds) {
  if (!std::isfinite(seconds)) return "n/a";
  if (seconds >= 1) return fmt("%.3g s", seconds);
  if (seconds >= 1e-3) return fmt("%.3g ms", seconds * 1e3);
  if (seconds >= 1e-6) return fmt("%.3g us", seconds * 1e6);
  return fmt("%.3g ns", seconds * 1e9);
}

/// A plotted value in its unit: a duration, or bytes.
std::string valueText(double v, const std::string& valueUnit) {
  if (valueUnit == "bytes") return std::isfinite(v) ? fmt("%.4g bytes", v) : "n/a";
  return duration(v);
}
bool answersDiffer(const std::string& agreement) {
  const std::string a = lower(agreement);
  return a.rfind("disagree", 0) == 0 || a.find("differ") != std::string::npos;
}

double relativeSpread(const std::vector<double>& runs) {
  std::vector<double> v;
  for (const double x : runs)
    if (std::isfinite(x)) v.push_back(x);
  if (v.size() < 2) return std::nan("");
  std::sort(v.begin(), v.end());
  const double median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  return median > 0 ? (v.back() - v.front()) / median : std::nan("");
}

std::string backendName(const std::string& backend) {
  static const std::map<std::string, std::string> names = {
      {"crux", "crux"}, {"embree", "Embree"}, {"bullet", "Bullet"}, {"fcl", "FCL"}, {"libccd", "libccd"},
      {"native", "native (crux)"}, {"exact", "exact (CGAL)"}};
  const auto it = names.find(backend);
  return it == names.end() ? backend : it->second;
}

const Entry* HeadRow::peer(const std::string& backend) const {
  for (const auto& [b, e] : peers)
    if (b == backend) return &e;
  return nullptr;
}

std::vector<HeadRow> headRows(const Json& results, std::vector<std::string>* peersOut) {
  const std::vector<WorkloadFigures> all = figures(results);
  std::vector<std::string> peers;
  for (const WorkloadFigures& f : all)
    for (const Entry& e : f.entries)
      if (e.backend != "crux" && std::find(peers.begin(), peers.end(), e.backend) == peers.end()) peers.push_back(e.backend);
  // A fixed column order (the README's), others after in order of appearance.
  const std::vector<std::string> preferred = {"embree", "bullet", "fcl", "libccd"};
  const auto rank = [&preferred](const std::string& p) {
    return std::size_t(std::find(preferred.begin(), preferred.end(), p) - preferred.begin());
  };
  std::stable_sort(peers.begin(), peers.end(), [&rank](const std::string& a, const std::string& b) { return rank(a) < rank(b); });
  if (peersOut) *peersOut = peers;
  std::vector<HeadRow> rows;
  for (const WorkloadFigures& f : all) {
    if (f.entries.empty() || f.entries[0].backend != "crux") continue;
    HeadRow row;
    row.workload = f.bench + "/" + f.key;
    row.title = f.bench + ": " + f.title;
    row.crux = f.entries[0];
    row.valueUnit = f.valueUnit;
    if (f.sizeName.empty()) {
      const auto benches = results.find("benches");
      const Json* d = benches != results.end() && benches->contains(f.bench) ? &(*benches)[f.bench] : nullptr;
      if (d && d->contains("data") && (*d)["data"].is_object() && (*d)["data"].contains("triangles"))
        row.input = fmt("%.0f triangles", num((*d)["data"], "triangles"));
    } else {
      row.input = fmt("%.0f ", row.crux.size) + f.sizeName;
    }
    row.unit = f.unit;
    // bench_parallel counts "rays", "queries", "triangles": per one of them.
    if (row.unit.size() > 3 && row.unit.compare(row.unit.size() - 3, 3, "ies") == 0) row.unit.replace(row.unit.size() - 3, 3, "y");
    else if (row.unit.size() > 3 && row.unit.back() == 's') row.unit.pop_back();
    for (const std::string& peer : peers)
      for (const Entry& e : f.entries)
        if (e.backend == peer && std::isfinite(e.seconds)) {
          row.peers.emplace_back(peer, e);
          break;
        }
    rows.push_back(row);
  }
  return rows;
}

}  // namespace crux::cli::report
