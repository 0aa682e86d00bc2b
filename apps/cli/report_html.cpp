/// @file report_html.cpp  The views of `crux report`: the plotted series (results.json
/// "series"), index.html with inline SVG charts (horizontal bars on a log axis for time ratios,
/// log-log lines for scaling) and tables, and summary.md.

#include "cli/report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace crux::cli {
namespace {

using Json = nlohmann::json;

// ---- normalised bench figures ------------------------------------------------------------------

/// One engine's time (or memory) on one workload at one size.
struct Entry {
  std::string backend;  ///< crux, embree, fcl, bullet, ... (lower-case first word of the engine name)
  std::string label;    ///< engine [config]
  double seconds = 0;   ///< per query / frame / build (the bench's reported clock); bytes for memory
  std::string agreement;
  double size = 0;      ///< triangles or models (0: one fixed input)
};

/// One workload of one bench: entries[0] is the reference (crux).
struct WorkloadFigures {
  std::string bench, key, title, unit, sizeName;
  std::string valueUnit = "seconds";  ///< what Entry::seconds holds: "seconds" or "bytes"
  std::vector<Entry> entries;  ///< at the largest size
  std::vector<Entry> sweep;    ///< every size (scaling benches)
};

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

std::string str(const Json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::string();
}

double num(const Json& j, const char* key, double fallback = 0) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : fallback;
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

std::vector<std::string> backendsOf(const std::vector<Entry>& entries) {
  std::vector<std::string> b;
  for (const Entry& e : entries)
    if (std::find(b.begin(), b.end(), e.backend) == b.end()) b.push_back(e.backend);
  return b;
}

// ---- formatting --------------------------------------------------------------------------------

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

/// Exact text of a double (round-trips through strtod), for data-* attributes.
std::string exact(double v) { return fmt("%.17g", v); }

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

std::string html(const std::string& s) {
  std::string out;
  for (const char ch : s) {
    switch (ch) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += ch;
    }
  }
  return out;
}

std::string colorOf(const std::string& backend) {
  static const std::map<std::string, std::string> colors = {
      {"crux", "#1b7837"}, {"embree", "#2166ac"}, {"fcl", "#b2182b"}, {"bullet", "#e08214"}, {"libccd", "#762a83"}};
  const auto it = colors.find(backend);
  return it == colors.end() ? "#555555" : it->second;
}

std::string scalar(const Json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_float()) return fmt("%.4g", v.get<double>());
  return v.dump();
}

// ---- SVG charts --------------------------------------------------------------------------------

/// Powers of ten spanning [lo, hi] (lo, hi > 0).
std::pair<double, double> decades(double lo, double hi) {
  return {std::pow(10.0, std::floor(std::log10(lo))), std::pow(10.0, std::ceil(std::log10(hi) + 1e-12))};
}

std::string decadeLabel(double v) {
  if (v >= 1e3 || v < 1e-2) return fmt("1e%.0f", std::log10(v));
  return fmt("%g", v);
}

/// Horizontal bars of one ratio series on a log axis, each bar drawn from 1 to its value.
std::string barChart(const std::string& id, const Json& s) {
  const Json& points = s["points"];
  std::vector<double> ys;
  for (const Json& p : points)
    if (p["y"].is_number() && p["y"].get<double>() > 0) ys.push_back(p["y"].get<double>());
  if (ys.empty()) return "<p>(no figures)</p>";
  const auto [lo, hi] = decades(std::min(0.5, *std::min_element(ys.begin(), ys.end())),
                                std::max(2.0, *std::max_element(ys.begin(), ys.end())));
  const double left = 300, width = 420, barH = 20, top = 30;
  const double height = top + barH * double(points.size()) + 30;
  const auto x = [&, lo = lo, hi = hi](double v) { return left + width * std::log10(v / lo) / std::log10(hi / lo); };
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"chart\" font-family=\"sans-serif\" font-size=\"11\" width=\"760\" height=\"" << height
    << "\" data-series=\"" << html(id) << "\">\n";
  o << "<text x=\"10\" y=\"18\" font-weight=\"bold\" font-size=\"12\">" << html(str(s, "title")) << "</text>\n";
  for (double d = lo; d <= hi * 1.0001; d *= 10) {
    o << "<line x1=\"" << x(d) << "\" y1=\"" << top - 4 << "\" x2=\"" << x(d) << "\" y2=\"" << height - 24
      << "\" stroke=\"#dddddd\"/><text x=\"" << x(d) << "\" y=\"" << height - 10 << "\" text-anchor=\"middle\" fill=\"#555555\">" << decadeLabel(d)
      << "</text>\n";
  }
  o << "<line x1=\"" << x(1) << "\" y1=\"" << top - 6 << "\" x2=\"" << x(1) << "\" y2=\"" << height - 24
    << "\" stroke=\"#000000\" stroke-width=\"1.5\"/>\n";
  double y = top;
  for (const Json& p : points) {
    const double v = p["y"].is_number() ? p["y"].get<double>() : 0;
    const std::string label = p["x"].is_string() ? p["x"].get<std::string>() : scalar(p["x"]);
    o << "<text x=\"" << left - 6 << "\" y=\"" << y + 14 << "\" text-anchor=\"end\">" << html(label) << "</text>\n";
    if (v > 0) {
      const double a = std::min(x(1), x(v)), b = std::max(x(1), x(v));
      o << "<rect x=\"" << a << "\" y=\"" << y + 3 << "\" width=\"" << std::max(1.0, b - a) << "\" height=\"" << barH - 6
        << "\" fill=\"" << colorOf(str(p, "backend")) << "\" data-series=\"" << html(id) << "\" data-x=\"" << html(label)
        << "\" data-y=\"" << exact(v) << "\"><title>" << html(label) << ": " << fmt("%.3g", v) << "x ("
        << html(str(p, "agreement")) << ")</title></rect>\n";
      o << "<text x=\"" << b + 4 << "\" y=\"" << y + 14 << "\" fill=\"#333333\">" << fmt("%.3g", v) << "x"
        << (str(p, "agreement") == "DISAGREE" || str(p, "agreement").rfind("DISAGREE", 0) == 0 ? " (answers differ)" : "")
        << "</text>\n";
    }
    y += barH;
  }
  o << "</svg>\n";
  return o.str();
}

/// Log-log lines, one per series (x = size, y = seconds per item).
std::string lineChart(const std::vector<std::pair<std::string, const Json*>>& series, const std::string& title,
                      const std::string& xLabel, const std::string& yLabel) {
  const std::string valueUnit = series.empty() ? "seconds" : str(*series.front().second, "value_unit");
  double xlo = 1e300, xhi = 0, ylo = 1e300, yhi = 0;
  for (const auto& [id, s] : series)
    for (const Json& p : (*s)["points"]) {
      if (!p["x"].is_number() || !p["y"].is_number() || p["x"].get<double>() <= 0 || p["y"].get<double>() <= 0) continue;
      xlo = std::min(xlo, p["x"].get<double>());
      xhi = std::max(xhi, p["x"].get<double>());
      ylo = std::min(ylo, p["y"].get<double>());
      yhi = std::max(yhi, p["y"].get<double>());
    }
  if (xhi <= 0 || yhi <= 0) return "<p>(no figures)</p>";
  const auto [x0, x1] = decades(xlo, xhi);
  const auto [y0, y1] = decades(ylo, yhi);
  const double left = 70, top = 46, w = 440, h = 260;
  const auto px = [&, x0 = x0, x1 = x1](double v) { return left + w * std::log10(v / x0) / std::log10(x1 / x0); };
  const auto py = [&, y0 = y0, y1 = y1](double v) { return top + h - h * std::log10(v / y0) / std::log10(y1 / y0); };
  std::ostringstream o;
  std::string ids;
  for (const auto& [id, s] : series) ids += (ids.empty() ? "" : " ") + id;
  const double height = std::max(top + h + 50, top + 16.0 * double(series.size()) + 20);
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"chart\" font-family=\"sans-serif\" font-size=\"11\" width=\"900\" height=\"" << height
    << "\" data-series=\"" << html(ids) << "\">\n";
  o << "<text x=\"10\" y=\"18\" font-weight=\"bold\" font-size=\"12\">" << html(title) << "</text>\n";
  for (double d = x0; d <= x1 * 1.0001; d *= 10)
    o << "<line x1=\"" << px(d) << "\" y1=\"" << top << "\" x2=\"" << px(d) << "\" y2=\"" << top + h
      << "\" stroke=\"#dddddd\"/><text x=\"" << px(d) << "\" y=\"" << top + h + 16 << "\" text-anchor=\"middle\" fill=\"#555555\">" << decadeLabel(d)
      << "</text>\n";
  for (double d = y0; d <= y1 * 1.0001; d *= 10)
    o << "<line x1=\"" << left << "\" y1=\"" << py(d) << "\" x2=\"" << left + w << "\" y2=\"" << py(d)
      << "\" stroke=\"#dddddd\"/><text x=\"" << left - 6 << "\" y=\"" << py(d) + 4 << "\" text-anchor=\"end\">"
      << html(valueText(d, valueUnit)) << "</text>\n";
  o << "<text x=\"" << left + w / 2 << "\" y=\"" << top + h + 36 << "\" text-anchor=\"middle\" fill=\"#555555\">" << html(xLabel)
    << " (log)</text>\n<text x=\"12\" y=\"" << top - 8 << "\" fill=\"#555555\">" << html(yLabel) << " (log)</text>\n";
  double legendY = top + 8;
  const std::string dashes[] = {"", "6,3", "2,3", "8,3,2,3"};
  std::map<std::string, int> perBackend;
  for (const auto& [id, s] : series) {
    const std::string backend = (*s)["backends"].empty() ? "" : (*s)["backends"][0].get<std::string>();
    const std::string color = colorOf(backend);
    const std::string dash = dashes[perBackend[backend]++ % 4];
    std::string pts;
    std::ostringstream marks;
    for (const Json& p : (*s)["points"]) {
      if (!p["x"].is_number() || !p["y"].is_number() || p["y"].get<double>() <= 0) continue;
      const double vx = p["x"].get<double>(), vy = p["y"].get<double>();
      pts += fmt("%.1f,", px(vx)) + fmt("%.1f ", py(vy));
      marks << "<circle cx=\"" << px(vx) << "\" cy=\"" << py(vy) << "\" r=\"3\" fill=\"" << color << "\" data-series=\""
            << html(id) << "\" data-x=\"" << exact(vx) << "\" data-y=\"" << exact(vy) << "\"><title>" << html(str(*s, "name"))
            << ": " << html(valueText(vy, valueUnit)) << " at " << fmt("%.0f", vx) << "</title></circle>\n";
    }
    o << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"1.5\""
      << (dash.empty() ? "" : " stroke-dasharray=\"" + dash + "\"") << " points=\"" << pts << "\"/>\n"
      << marks.str();
    o << "<line x1=\"" << left + w + 20 << "\" y1=\"" << legendY - 4 << "\" x2=\"" << left + w + 44 << "\" y2=\""
      << legendY - 4 << "\" stroke=\"" << color << "\" stroke-width=\"2\""
      << (dash.empty() ? "" : " stroke-dasharray=\"" + dash + "\"") << "/><text x=\"" << left + w + 50 << "\" y=\""
      << legendY << "\">" << html(str(*s, "name")) << "</text>\n";
    legendY += 16;
  }
  o << "</svg>\n";
  return o.str();
}

// ---- tables ------------------------------------------------------------------------------------

/// A JSON value as HTML: objects of objects and arrays of objects become tables, scalars text.
std::string jsonHtml(const Json& v, int depth = 0) {
  if (!v.is_object() && !v.is_array()) return html(scalar(v));
  if (depth > 3) return "<code>" + html(v.dump()) + "</code>";
  std::vector<std::pair<std::string, const Json*>> rows;
  if (v.is_object())
    for (const auto& [k, x] : v.items()) rows.emplace_back(k, &x);
  else
    for (std::size_t i = 0; i < v.size(); ++i) rows.emplace_back(std::to_string(i), &v[i]);
  bool tabular = !rows.empty();
  std::vector<std::string> columns;
  for (const auto& [k, x] : rows) {
    if (!x->is_object()) {
      tabular = false;
      break;
    }
    for (const auto& [c, y] : x->items())
      if (std::find(columns.begin(), columns.end(), c) == columns.end()) columns.push_back(c);
  }
  std::ostringstream o;
  o << "<table>";
  if (tabular) {
    o << "<tr><th></th>";
    for (const std::string& c : columns) o << "<th>" << html(c) << "</th>";
    o << "</tr>";
    for (const auto& [k, x] : rows) {
      o << "<tr><td>" << html(k) << "</td>";
      for (const std::string& c : columns) o << "<td>" << (x->contains(c) ? jsonHtml((*x)[c], depth + 1) : "") << "</td>";
      o << "</tr>";
    }
  } else {
    for (const auto& [k, x] : rows) o << "<tr><th>" << html(k) << "</th><td>" << jsonHtml(*x, depth + 1) << "</td></tr>";
  }
  o << "</table>";
  return o.str();
}

/// The headline: per workload, crux's time and each peer's time relative to crux.
struct Headline {
  std::vector<std::string> peers;
  std::vector<std::vector<std::string>> rows;  ///< workload, input, crux, one cell per peer
};

Headline headline(const Json& results) {
  Headline h;
  const std::vector<WorkloadFigures> all = figures(results);
  for (const WorkloadFigures& f : all)
    for (const Entry& e : f.entries)
      if (e.backend != "crux" && std::find(h.peers.begin(), h.peers.end(), e.backend) == h.peers.end())
        h.peers.push_back(e.backend);
  // A fixed column order (the README's), others after in order of appearance.
  const std::vector<std::string> preferred = {"embree", "bullet", "fcl", "libccd"};
  const auto rank = [&preferred](const std::string& p) {
    return std::size_t(std::find(preferred.begin(), preferred.end(), p) - preferred.begin());
  };
  std::stable_sort(h.peers.begin(), h.peers.end(),
                   [&rank](const std::string& a, const std::string& b) { return rank(a) < rank(b); });
  for (const WorkloadFigures& f : all) {
    if (f.entries.empty() || f.entries[0].backend != "crux") continue;
    const Entry& crux = f.entries[0];
    std::vector<std::string> row = {f.bench + ": " + f.title};
    if (f.sizeName.empty()) {
      const Json& d = results["benches"][f.bench]["data"];
      row.push_back(d.contains("triangles") ? fmt("%.0f triangles", num(d, "triangles")) : "");
    } else {
      row.push_back(fmt("%.0f ", crux.size) + f.sizeName);
    }
    std::string unit = f.unit;
    // bench_parallel counts "rays", "queries", "triangles": per one of them.
    if (unit.size() > 3 && unit.compare(unit.size() - 3, 3, "ies") == 0) unit.replace(unit.size() - 3, 3, "y");
    else if (unit.size() > 3 && unit.back() == 's') unit.pop_back();
    row.push_back(valueText(crux.seconds, f.valueUnit) + "/" + unit);
    for (const std::string& peer : h.peers) {
      std::string cell = "-";
      for (const Entry& e : f.entries)
        if (e.backend == peer && std::isfinite(e.seconds) && crux.seconds > 0) {
          const std::string agree = lower(e.agreement);
          cell = fmt("%.2fx", e.seconds / crux.seconds) +
                 (agree.rfind("disagree", 0) == 0 || agree.find("differ") != std::string::npos ? " (answers differ)" : "");
          break;
        }
      row.push_back(cell);
    }
    h.rows.push_back(row);
  }
  return h;
}

std::string machineLine(const Json& results) {
  const Json& m = results["machine"];
  return str(m, "cpu") + ", " + std::to_string(m.value("hardware_threads", 0)) + " hardware threads, " +
         str(m, "compiler") + " " + str(m, "build_type") + ", crux::Real = " + str(m, "crux_real");
}

std::string sanityLine(const Json& s) {
  if (!s.value("available", false)) return "not available in this build (" + str(s, "reason") + ")";
  if (!s.contains("tests")) return "did not produce results (exit " + scalar(s["exit_status"]) + ")";
  return std::to_string(s["tests"].get<int>() - s["failures"].get<int>()) + " of " + scalar(s["tests"]) +
         " sanity tests pass (native, exact, FCL, Bullet agree on unambiguous cases)";
}

/// Per backend, the verdict counts of `crux diff`'s op x backend table summed over ops
/// ({"table": {op: {backend: {verdict: count}}}}); empty when the table has another shape.
std::map<std::string, std::map<std::string, double>> diffTotals(const Json& d) {
  std::map<std::string, std::map<std::string, double>> totals;
  const auto data = d.find("data");
  if (data == d.end() || !data->is_object() || !data->contains("table") || !(*data)["table"].is_object()) return totals;
  for (const auto& [op, backends] : (*data)["table"].items()) {
    if (!backends.is_object()) continue;
    for (const auto& [backend, verdicts] : backends.items()) {
      if (!verdicts.is_object()) continue;
      for (const auto& [verdict, count] : verdicts.items())
        if (count.is_number()) totals[backend][verdict] += count.get<double>();
    }
  }
  return totals;
}

std::string diffLine(const Json& d) {
  if (!d.value("available", false)) return str(d, "reason");
  return "ran for the budget (exit " + scalar(d["exit_status"]) + (d["exit_status"] == 1 ? ": crux answered wrong" : "") +
         "); op x backend table below";
}

}  // namespace

nlohmann::json chartSeries(const nlohmann::json& results) {
  Json series = Json::object();
  for (const WorkloadFigures& f : figures(results)) {
    const std::string base = f.bench + "." + f.key;
    const std::string workload = f.bench + "/" + f.key;
    // Ratio bars at the (largest) size: engine time / crux time.
    if (!f.entries.empty() && f.entries[0].backend == "crux" && f.entries[0].seconds > 0) {
      const bool bytes = f.valueUnit == "bytes";
      Json s = {{"kind", "bar"}, {"chart", base + ".ratio"}, {"workload", workload}, {"unit", "ratio"},
                {"value_unit", f.valueUnit}, {"crux_value", f.entries[0].seconds}};
      s["title"] = f.bench + ": " + f.title + (f.sizeName.empty() ? "" : fmt(", %.0f ", f.entries[0].size) + f.sizeName) +
                   (bytes ? " - relative to crux's " + valueText(f.entries[0].seconds, "bytes") + " (> 1: crux is smaller)"
                          : " - time relative to " + f.entries[0].label + " (> 1: crux is faster)");
      s["backends"] = backendsOf(f.entries);
      Json points = Json::array();
      for (std::size_t i = 1; i < f.entries.size(); ++i) {
        const Entry& e = f.entries[i];
        if (!std::isfinite(e.seconds)) continue;
        points.push_back({{"x", e.label}, {"y", e.seconds / f.entries[0].seconds}, {"backend", e.backend},
                          {"agreement", e.agreement}, {bytes ? "bytes" : "seconds", e.seconds}});
      }
      s["points"] = points;
      if (!points.empty()) series[base + ".ratio"] = s;
    }
    // Scaling lines: one series per engine.
    std::vector<std::string> labels;
    for (const Entry& e : f.sweep)
      if (std::find(labels.begin(), labels.end(), e.label) == labels.end()) labels.push_back(e.label);
    for (const std::string& label : labels) {
      Json s = {{"kind", "line"}, {"chart", base + ".scaling"}, {"workload", workload}, {"name", label},
                {"title", f.bench + ": " + f.title + (f.valueUnit == "bytes" ? " - bytes vs size" : " - cost vs size")}, {"x_label", f.sizeName},
                {"y_label", (f.valueUnit == "bytes" ? "bytes per " : "time per ") + f.unit}, {"unit", f.valueUnit},
                {"value_unit", f.valueUnit}};
      Json points = Json::array();
      std::string backend;
      for (const Entry& e : f.sweep)
        if (e.label == label && std::isfinite(e.seconds)) {
          points.push_back({{"x", e.size}, {"y", e.seconds}, {"agreement", e.agreement}});
          backend = e.backend;
        }
      s["backends"] = Json::array({backend});
      s["points"] = points;
      series[base + ".scaling." + slug(label)] = s;
    }
  }
  const auto cg = results.find("callgrind");
  if (cg != results.end() && cg->value("available", false)) {
    const Json& b = (*cg)["backends"];
    if (b.contains("crux") && b["crux"].is_object()) {
      Json s = {{"kind", "bar"}, {"chart", "callgrind.rays"}, {"workload", "callgrind/rays"}, {"unit", "ratio"},
                {"title", "callgrind: instructions per ray relative to crux (10k-triangle torus)"}};
      Json points = Json::array(), backends = Json::array({"crux"});
      const double crux = b["crux"]["instructions_per_ray"].get<double>();
      for (const auto& [name, v] : b.items())
        if (name != "crux" && v.is_object()) {
          points.push_back({{"x", name}, {"y", v["instructions_per_ray"].get<double>() / crux}, {"backend", name},
                            {"agreement", ""}});
          backends.push_back(name);
        }
      s["points"] = points;
      s["backends"] = backends;
      if (!points.empty()) series["callgrind.rays"] = s;
    }
  }
  return series;
}

std::string renderSummary(const nlohmann::json& results) {
  std::ostringstream o;
  const Json& r = results["report"];
  o << "# crux report (" << str(r, "budget") << ")\n\n"
    << str(r, "date") << " on " << machineLine(results) << "; took " << fmt("%.0f", num(r, "seconds")) << " s.\n\n"
    << "## Cross-validation\n\n"
    << "- oracle sanity suite: " << sanityLine(results["cross_validation"]["sanity"]) << "\n"
    << "- crux diff: " << diffLine(results["cross_validation"]["diff"]) << "\n";
  const Json& diff = results["cross_validation"]["diff"];
  for (const auto& [backend, verdicts] : diffTotals(diff)) {
    o << "  - " << backend << ":";
    for (const auto& [verdict, count] : verdicts) o << " " << verdict << " " << fmt("%.0f", count) << ";";
    o << "\n";
  }
  if (diff.contains("data") && diff["data"].is_object() && diff["data"].contains("peer_causes"))
    o << "  - peer disagreements by cause: `" << diff["data"]["peer_causes"].dump() << "`\n";
  o << "\n"
    << "## Performance (peer time / crux time: > 1 means crux is faster)\n\n";
  const Headline h = headline(results);
  o << "| workload | input | crux |";
  for (const std::string& p : h.peers) o << " " << p << " |";
  o << "\n|---|---|---|";
  for (std::size_t i = 0; i < h.peers.size(); ++i) o << "---|";
  o << "\n";
  for (const auto& row : h.rows) {
    o << "|";
    for (const std::string& cell : row) o << " " << cell << " |";
    o << "\n";
  }
  o << "\nAnswers are compared on every query before timing; \"answers differ\" marks a peer that disagreed "
       "(see the bench logs in raw/). Memory rows: peer bytes / crux bytes (> 1: crux is smaller).\n";
  for (const auto& [bench, step] : results["benches"].items())
    if (!step.value("available", false)) o << "\n- " << bench << ": not available in this build";
  o << "\n";
  return o.str();
}

std::string renderHtml(const nlohmann::json& results) {
  std::ostringstream o;
  const Json& r = results["report"];
  o << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>crux report</title>\n<style>\n"
       "body{font-family:sans-serif;max-width:1000px;margin:1em auto;color:#222}"
       "table{border-collapse:collapse;margin:.5em 0;font-size:13px}td,th{border:1px solid #ccc;padding:2px 6px;"
       "text-align:left;vertical-align:top}"
       "svg.chart{display:block;margin:1em 0;font-size:11px}.title{font-weight:bold;font-size:12px}"
       ".grid{stroke:#ddd}.one{stroke:#000;stroke-width:1.5}.tick{text-anchor:middle;fill:#555}"
       ".label{text-anchor:end}.value{fill:#333}.axis{fill:#555}.legend{fill:#222}\n"
       "</style></head><body>\n";
  o << "<h1>crux report</h1>\n<p>" << html(str(r, "date")) << ", budget <b>" << html(str(r, "budget")) << "</b>, "
    << fmt("%.0f", num(r, "seconds")) << " s. Raw figures: <a href=\"results.json\">results.json</a>; "
    << "terminal summary: <a href=\"summary.md\">summary.md</a>.</p>\n";
  o << "<h2>Machine</h2>\n" << jsonHtml(results["machine"]) << "\n";

  o << "<h2>Cross-validation</h2>\n<h3>Oracle sanity suite</h3>\n<p>"
    << html(sanityLine(results["cross_validation"]["sanity"])) << "</p>\n";
  const Json& sanity = results["cross_validation"]["sanity"];
  if (sanity.contains("cases")) {
    o << "<table><tr><th>test</th><th>result</th></tr>";
    for (const Json& t : sanity["cases"])
      o << "<tr><td>" << html(str(t, "name")) << "</td><td>" << (t.value("passed", false) ? "pass" : "FAIL") << "</td></tr>";
    o << "</table>\n";
  }
  const Json& diff = results["cross_validation"]["diff"];
  o << "<h3>crux diff</h3>\n<p>" << html(diffLine(diff)) << "</p>\n";
  if (diff.value("available", false)) {
    if (diff.contains("data") && !diff["data"].is_null()) o << jsonHtml(diff["data"]) << "\n";
    o << "<p>command: <code>" << html(str(diff, "command")) << "</code></p>\n";
  }

  o << "<h2>Headline (peer time / crux time: &gt; 1 means crux is faster)</h2>\n";
  const Headline h = headline(results);
  o << "<table><tr><th>workload</th><th>input</th><th>crux</th>";
  for (const std::string& p : h.peers) o << "<th>" << html(p) << "</th>";
  o << "</tr>\n";
  for (const auto& row : h.rows) {
    o << "<tr>";
    for (const std::string& cell : row) o << "<td>" << html(cell) << "</td>";
    o << "</tr>\n";
  }
  o << "</table>\n";

  const Json& series = results["series"];
  for (const auto& [bench, step] : results["benches"].items()) {
    o << "<h2>" << html(bench) << "</h2>\n";
    if (!step.value("available", false)) {
      o << "<p>not available in this build: " << html(str(step, "reason")) << "</p>\n";
      continue;
    }
    o << "<p><code>" << html(str(step, "command")) << "</code>: exit " << html(scalar(step["exit_status"])) << ", "
      << fmt("%.1f", num(step, "seconds")) << " s; log <a href=\"" << html(str(step, "log")) << "\">"
      << html(str(step, "log")) << "</a></p>\n";
    // Charts of this bench, grouped by their "chart" field, in series order.
    std::vector<std::string> charts;
    std::map<std::string, std::vector<std::pair<std::string, const Json*>>> members;
    for (const auto& [id, s] : series.items()) {
      if (id.rfind(bench + ".", 0) != 0) continue;
      const std::string chart = str(s, "chart");
      if (!members.count(chart)) charts.push_back(chart);
      members[chart].emplace_back(id, &s);
    }
    for (const std::string& chart : charts) {
      const auto& m = members[chart];
      const Json& first = *m.front().second;
      if (str(first, "kind") == "bar") {
        o << barChart(m.front().first, first);
      } else if (m.front().second->value("points", Json::array()).size() > 1) {
        o << lineChart(m, str(first, "title"), str(first, "x_label"), str(first, "y_label"));
      }
    }
    // Table of times per workload.
    const Json& data = step["data"];
    std::vector<WorkloadFigures> mine;
    for (const WorkloadFigures& f : figures(results))
      if (f.bench == bench) mine.push_back(f);
    for (const WorkloadFigures& f : mine) {
      o << "<h3>" << html(f.title) << "</h3>\n<table><tr><th>engine</th>" << (f.sizeName.empty() ? "" : "<th>" + f.sizeName + "</th>")
        << "<th>" << (f.valueUnit == "bytes" ? "bytes" : "time") << " per " << html(f.unit) << "</th><th>vs crux</th><th>answers</th></tr>\n";
      const std::vector<Entry>& rows = f.sweep.empty() ? f.entries : f.sweep;
      std::map<double, double> cruxAt;
      for (const Entry& e : rows)
        if (e.backend == "crux" && !cruxAt.count(e.size)) cruxAt[e.size] = e.seconds;
      for (const Entry& e : rows) {
        const double ref = cruxAt.count(e.size) ? cruxAt[e.size] : std::nan("");
        o << "<tr><td>" << html(e.label) << "</td>" << (f.sizeName.empty() ? "" : "<td>" + fmt("%.0f", e.size) + "</td>")
          << "<td>" << html(valueText(e.seconds, f.valueUnit)) << "</td><td>" << (ref > 0 ? fmt("%.2fx", e.seconds / ref) : "")
          << "</td><td>" << html(e.agreement) << "</td></tr>\n";
      }
      o << "</table>\n";
    }
    if (data.is_object() && data.contains("targets")) o << "<h3>Targets</h3>\n" << jsonHtml(data["targets"]) << "\n";
    if (data.is_object() && data.contains("memory")) o << "<h3>Memory</h3>\n" << jsonHtml(data["memory"]) << "\n";
    if (mine.empty() && data.is_object()) o << "<h3>Figures</h3>\n" << jsonHtml(data) << "\n";
    if (step.contains("text")) o << "<p>(no JSON output: its printed tables)</p><pre>" << html(str(step, "text")) << "</pre>\n";
  }
  const auto cg = results.find("callgrind");
  if (cg != results.end()) {
    o << "<h2>callgrind</h2>\n";
    if (series.contains("callgrind.rays")) o << barChart("callgrind.rays", series["callgrind.rays"]);
    o << jsonHtml(*cg) << "\n";
  }
  o << "</body></html>\n";
  return o.str();
}

}  // namespace crux::cli
