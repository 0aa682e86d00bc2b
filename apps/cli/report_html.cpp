/// @file report_html.cpp  The views of `crux report`: the plotted series (results.json
/// "series"), index.html (the verdict first, then the cross-validation grid and disagreements,
/// the comparison with an older run, and per bench inline SVG charts: horizontal bars on a log
/// axis for time ratios, log-log lines with their fitted slope for scaling) and summary.md.

#include "cli/report.hpp"
#include "cli/report_figures.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace crux::cli {
namespace {

using Json = nlohmann::json;
using namespace report;

// ---- formatting --------------------------------------------------------------------------------

/// Exact text of a double (round-trips through strtod), for data-* attributes.
std::string exact(double v) { return fmt("%.17g", v); }

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

/// The count j[key] as text; "0" when absent.
std::string count(const Json& j, const char* key) { return fmt("%.0f", num(j, key)); }

/// "1 regression", "2 regressions": the count j[key] and `noun`, plural unless it is 1.
std::string counted(const Json& j, const char* key, const std::string& noun) {
  return count(j, key) + " " + noun + (num(j, key) == 1 ? "" : "s");
}

/// A batch-protocol answer in readable form: `key: value, ...` (without the echoed id and op),
/// vectors as [x, y, z].
std::string answerText(const Json& v, bool top = true) {
  if (v.is_number_integer()) return v.dump();
  if (v.is_number()) return fmt("%.7g", v.get<double>());
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + answerText(v[i], false);
    return s + "]";
  }
  if (v.is_object()) {
    std::string s;
    for (const auto& [k, x] : v.items())
      if (!top || (k != "id" && k != "op")) s += (s.empty() ? "" : ", ") + k + ": " + answerText(x, false);
    return top ? s : "{" + s + "}";
  }
  return v.dump();
}

std::vector<std::string> backendsOf(const std::vector<Entry>& entries) {
  std::vector<std::string> b;
  for (const Entry& e : entries)
    if (std::find(b.begin(), b.end(), e.backend) == b.end()) b.push_back(e.backend);
  return b;
}

// ---- SVG charts --------------------------------------------------------------------------------

/// Chart geometry: every chart is drawn in its own coordinates (viewBox) and scaled to the page
/// width by CSS, so nothing depends on the window size; text widths are estimated from the
/// character count (sans-serif averages ~0.6 em; the browser test measures the real widths).
constexpr double kChartWidth = 760;
constexpr double kFont = 11, kTitleFont = 12.5;

double textWidth(const std::string& s, double px, bool bold = false) {
  std::size_t chars = 0;
  for (const unsigned char ch : s) chars += (ch & 0xC0) != 0x80;  // UTF-8 code points
  return double(chars) * px * (bold ? 0.66 : 0.6);
}

/// Greedy word wrap to lines no wider than `width`.
std::vector<std::string> wrap(const std::string& text, double width, double px, bool bold) {
  std::vector<std::string> lines;
  std::istringstream words(text);
  std::string line;
  for (std::string w; words >> w;) {
    const std::string candidate = line.empty() ? w : line + " " + w;
    if (!line.empty() && textWidth(candidate, px, bold) > width) {
      lines.push_back(line);
      line = w;
    } else {
      line = candidate;
    }
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

/// The title (bold, wrapped) and the "what is better" line of a chart; returns the y below them.
double chartHeading(std::ostringstream& o, double width, const std::string& title, const std::string& better) {
  double y = 18;
  for (const std::string& line : wrap(title, width - 20, kTitleFont, true)) {
    o << "<text class=\"title\" x=\"10\" y=\"" << y << "\" font-weight=\"bold\" font-size=\"" << kTitleFont << "\">"
      << html(line) << "</text>\n";
    y += 16;
  }
  for (const std::string& line : wrap(better, width - 20, kFont, false)) {
    o << "<text class=\"better\" x=\"10\" y=\"" << y << "\" fill=\"#444444\">" << html(line) << "</text>\n";
    y += 14;
  }
  return y;
}

std::string svgOpen(double width, double height, const std::string& ids) {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"chart\" viewBox=\"0 0 " + fmt("%.0f", width) + " " +
         fmt("%.0f", height) + "\" width=\"" + fmt("%.0f", width) + "\" height=\"" + fmt("%.0f", height) +
         "\" font-family=\"sans-serif\" font-size=\"" + fmt("%g", kFont) + "\" data-series=\"" + html(ids) + "\">\n";
}

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
  double labelWidth = 0;
  for (const Json& p : points) {
    if (p["y"].is_number() && p["y"].get<double>() > 0) ys.push_back(p["y"].get<double>());
    labelWidth = std::max(labelWidth, textWidth(p["x"].is_string() ? p["x"].get<std::string>() : scalar(p["x"]), kFont));
  }
  if (ys.empty()) return "<p>(no figures)</p>";
  const auto [lo, hi] = decades(std::min(0.5, *std::min_element(ys.begin(), ys.end())),
                                std::max(2.0, *std::max_element(ys.begin(), ys.end())));
  const double valueWidth = textWidth("0.000x (answers differ)", kFont) + 8;
  const double W = std::max(kChartWidth, 10 + labelWidth + 10 + 260 + valueWidth);
  const double left = 10 + labelWidth + 10, width = W - left - valueWidth, barH = 20;
  std::ostringstream body;
  const double top = chartHeading(body, W, str(s, "title"), str(s, "better")) + 6;
  const double height = top + barH * double(points.size()) + 46;
  const auto x = [&, lo = lo, hi = hi](double v) { return left + width * std::log10(v / lo) / std::log10(hi / lo); };
  std::ostringstream o;
  o << svgOpen(W, height, id) << body.str();
  const double axisY = top + barH * double(points.size());
  for (double d = lo; d <= hi * 1.0001; d *= 10) {
    o << "<line x1=\"" << x(d) << "\" y1=\"" << top - 4 << "\" x2=\"" << x(d) << "\" y2=\"" << axisY + 4
      << "\" stroke=\"#dddddd\"/><text x=\"" << x(d) << "\" y=\"" << axisY + 16 << "\" text-anchor=\"middle\" fill=\"#555555\">"
      << decadeLabel(d) << "</text>\n";
  }
  o << "<line x1=\"" << x(1) << "\" y1=\"" << top - 6 << "\" x2=\"" << x(1) << "\" y2=\"" << axisY + 4
    << "\" stroke=\"#000000\" stroke-width=\"1.5\"/>\n";
  // Which side is which, under the axis.
  const bool bytes = str(s, "value_unit") == "bytes";
  o << "<text x=\"" << x(1) - 6 << "\" y=\"" << axisY + 32 << "\" text-anchor=\"end\" fill=\"#555555\">&#8592; "
    << (bytes ? "peer smaller" : str(s, "unit") == "ratio" && id.rfind("callgrind", 0) == 0 ? "peer fewer" : "peer faster")
    << "</text><text x=\"" << x(1) + 6 << "\" y=\"" << axisY + 32 << "\" fill=\"#555555\">"
    << (bytes ? "crux smaller" : id.rfind("callgrind", 0) == 0 ? "crux fewer" : "crux faster") << " &#8594;</text>\n";
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
        << (answersDiffer(str(p, "agreement")) ? " (answers differ)" : "") << "</text>\n";
    }
    y += barH;
  }
  o << "</svg>\n";
  return o.str();
}

/// Log-log lines, one per series (x = size, y = seconds per item), each with its fitted slope.
std::string lineChart(const std::vector<std::pair<std::string, const Json*>>& series) {
  const Json& first = *series.front().second;
  const std::string valueUnit = str(first, "value_unit");
  double xlo = 1e300, xhi = 0, ylo = 1e300, yhi = 0, legendWidth = 0;
  std::vector<std::string> legends;
  for (const auto& [id, s] : series) {
    for (const Json& p : (*s)["points"]) {
      if (!p["x"].is_number() || !p["y"].is_number() || p["x"].get<double>() <= 0 || p["y"].get<double>() <= 0) continue;
      xlo = std::min(xlo, p["x"].get<double>());
      xhi = std::max(xhi, p["x"].get<double>());
      ylo = std::min(ylo, p["y"].get<double>());
      yhi = std::max(yhi, p["y"].get<double>());
    }
    const Json slope = s->value("slope", Json());
    legends.push_back(str(*s, "name") + (slope.is_number() ? fmt(" (slope %.2f)", slope.get<double>()) : ""));
    legendWidth = std::max(legendWidth, textWidth(legends.back(), kFont));
  }
  if (xhi <= 0 || yhi <= 0) return "<p>(no figures)</p>";
  const auto [x0, x1] = decades(xlo, xhi);
  const auto [y0, y1] = decades(ylo, yhi);
  const double left = 76, w = 400, h = 240;
  const double W = std::max(kChartWidth, left + w + 20 + 30 + legendWidth + 10);
  std::ostringstream body;
  const double top = chartHeading(body, W, str(first, "title"), str(first, "better")) + 22;
  const auto px = [&, x0 = x0, x1 = x1](double v) { return left + w * std::log10(v / x0) / std::log10(x1 / x0); };
  const auto py = [&, y0 = y0, y1 = y1](double v) { return top + h - h * std::log10(v / y0) / std::log10(y1 / y0); };
  std::string ids;
  for (const auto& [id, s] : series) ids += (ids.empty() ? "" : " ") + id;
  const double height = std::max(top + h + 46, top + 16.0 * double(series.size()) + 20);
  std::ostringstream o;
  o << svgOpen(W, height, ids) << body.str();
  for (double d = x0; d <= x1 * 1.0001; d *= 10)
    o << "<line x1=\"" << px(d) << "\" y1=\"" << top << "\" x2=\"" << px(d) << "\" y2=\"" << top + h
      << "\" stroke=\"#dddddd\"/><text x=\"" << px(d) << "\" y=\"" << top + h + 16 << "\" text-anchor=\"middle\" fill=\"#555555\">"
      << decadeLabel(d) << "</text>\n";
  for (double d = y0; d <= y1 * 1.0001; d *= 10)
    o << "<line x1=\"" << left << "\" y1=\"" << py(d) << "\" x2=\"" << left + w << "\" y2=\"" << py(d)
      << "\" stroke=\"#dddddd\"/><text x=\"" << left - 6 << "\" y=\"" << py(d) + 4 << "\" text-anchor=\"end\">"
      << html(valueText(d, valueUnit)) << "</text>\n";
  o << "<text x=\"" << left + w / 2 << "\" y=\"" << top + h + 34 << "\" text-anchor=\"middle\" fill=\"#555555\">"
    << html(str(first, "x_label")) << " (log scale)</text>\n<text x=\"10\" y=\"" << top - 10 << "\" fill=\"#555555\">"
    << html(str(first, "y_label")) << " (log scale)</text>\n";
  double legendY = top + 8;
  const std::string dashes[] = {"", "6,3", "2,3", "8,3,2,3"};
  std::map<std::string, int> perBackend;
  for (std::size_t i = 0; i < series.size(); ++i) {
    const auto& [id, s] = series[i];
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
    o << "<line x1=\"" << left + w + 20 << "\" y1=\"" << legendY - 4 << "\" x2=\"" << left + w + 44 << "\" y2=\"" << legendY - 4
      << "\" stroke=\"" << color << "\" stroke-width=\"2\"" << (dash.empty() ? "" : " stroke-dasharray=\"" + dash + "\"")
      << "/><text x=\"" << left + w + 50 << "\" y=\"" << legendY << "\">" << html(legends[i]) << "</text>\n";
    legendY += 16;
  }
  o << "</svg>\n";
  return o.str();
}

/// Least-squares slope of log(y) against log(x): the exponent k of y ~ x^k.
Json logLogSlope(const Json& points) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const Json& p : points) {
    if (!p["x"].is_number() || !p["y"].is_number() || p["x"].get<double>() <= 0 || p["y"].get<double>() <= 0) continue;
    const double lx = std::log(p["x"].get<double>()), ly = std::log(p["y"].get<double>());
    n += 1;
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  const double d = n * sxx - sx * sx;
  if (n < 2 || !(std::abs(d) > 0)) return nullptr;
  return (n * sxy - sx * sy) / d;
}

// ---- the verdict --------------------------------------------------------------------------------

std::string causesText(const Json& causes) {
  std::vector<std::pair<double, std::string>> sorted;
  for (const auto& [cause, n] : causes.items())
    if (n.is_number()) sorted.emplace_back(-n.get<double>(), cause);
  std::sort(sorted.begin(), sorted.end());
  std::string s;
  for (const auto& [n, cause] : sorted) s += (s.empty() ? "" : ", ") + cause + " " + fmt("%.0f", -n);
  return s;
}

/// The cross-validation verdict as lines (shared by index.html and summary.md; plain text).
std::vector<std::string> correctnessLines(const Json& c) {
  std::vector<std::string> lines;
  if (c.value("sanity_available", false))
    lines.push_back("oracle sanity suite: " + std::to_string(c.value("sanity_tests", 0) - c.value("sanity_failures", 0)) + " of " +
                    std::to_string(c.value("sanity_tests", 0)) + " pass");
  else
    lines.push_back("oracle sanity suite: not available in this build");
  const Json backends = c.value("backends", Json::object());
  for (const auto& [backend, b] : backends.items()) {
    if (backend == "native" || backend == "exact") continue;
    std::string line = backendName(backend) + ": " + count(b, "peer_wrong") + " wrong";
    const std::string causes = causesText(b.value("peer_wrong_causes", Json::object()));
    if (!causes.empty()) line += " (" + causes + ")";
    // Unsupported ops and cases without an arbiter are not compared.
    const double compared = num(b, "answers") - num(b, "unsupported") - num(b, "no_arbiter");
    line += ", " + count(b, "within_tolerance") + " within tolerance, " + count(b, "error") + " errors, of " +
            fmt("%.0f", compared) + " answers compared";
    lines.push_back(line);
  }
  return lines;
}

/// The headline of the cross-validation: crux's wrong answers, and what they were counted over.
std::pair<std::string, std::string> cruxWrongText(const Json& c) {
  if (!c.value("diff_available", false)) return {"crux diff did not run", str(c, "diff_reason")};
  return {counted(c, "crux_wrong", "crux-wrong answer"),
          "in " + count(c, "diff_cases") + " generated crux diff cases, every backend's answer judged against the exact (CGAL) backend"};
}

/// "bench_scaling: refit, 100000 triangles: 0.45x".
std::string worstText(const Json& p) {
  const Json& w = p["worst"];
  if (!w.is_object()) return "";
  return str(w, "title") + (str(w, "input").empty() ? "" : ", " + str(w, "input")) + ": ";
}

std::string verdictHtml(const Json& v) {
  std::ostringstream o;
  const Json& c = v["correctness"];
  // Green: crux diff ran and crux was never wrong; red: crux was wrong (or the sanity suite
  // failed); grey: nothing to judge by.
  const bool wrongSeen = c.value("crux_wrong", 0) > 0 || c.value("sanity_failures", 0) > 0;
  const std::string state = wrongSeen ? "bad" : c.value("diff_available", false) ? "ok" : "unknown";
  o << "<section id=\"verdict\">\n<h1>crux report</h1>\n<p class=\"machine\">" << html(str(v, "machine")) << " &middot; "
    << html(str(v, "build")) << " &middot; " << html(str(v, "run")) << "</p>\n<div class=\"cards\">\n";
  const auto [wrong, over] = cruxWrongText(c);
  o << "<div class=\"card " << state << "\"><h2>Is crux right?</h2>\n<p><span class=\"big\">" << html(wrong)
    << "</span> " << html(over) << "</p>\n<ul>";
  for (const std::string& line : correctnessLines(c)) o << "<li>" << html(line) << "</li>";
  o << "</ul>\n<p class=\"note\">Peers are judged against exact too; their disagreements, grouped by cause, are under "
       "<a href=\"#cross-validation\">Cross-validation</a>.</p></div>\n";
  o << "<div class=\"card perf\"><h2>Where is crux faster?</h2>\n";
  const Json& perf = v["performance"];
  if (perf.empty()) {
    o << "<p>No timed workload with a peer in this build (benches not built).</p>";
  } else {
    o << "<table class=\"verdict\"><tr><th>peer</th><th>crux faster</th><th>crux slower</th><th>geometric mean of "
         "peer&nbsp;/&nbsp;crux time</th><th>worst row for crux</th></tr>\n";
    for (const Json& p : perf) {
      const Json& g = p["geomean"];
      o << "<tr><td><b>" << html(str(p, "name")) << "</b></td><td class=\"num\">" << count(p, "crux_faster") << " of "
        << count(p, "workloads") << "</td><td class=\"num\">" << count(p, "crux_slower") << " of " << count(p, "workloads")
        << "</td><td class=\"num "
        << (g.is_number() && g.get<double>() >= 1 ? "win" : "loss") << "\">"
        << (g.is_number() ? fmt("%.2fx", g.get<double>()) : "-") << "</td><td>";
      if (p["worst"].is_object()) o << html(worstText(p)) << "<b>" << fmt("%.2fx", num(p["worst"], "ratio")) << "</b>";
      if (num(p, "answers_differ") > 0)
        o << "<br><span class=\"note\">" << count(p, "answers_differ") << " more with different answers, not counted</span>";
      o << "</td></tr>\n";
    }
    o << "</table>\n<p class=\"note\">Per workload, peer time / crux time: &gt; 1 means crux is faster. Memory rows are "
         "not counted; every row is in <a href=\"#workloads\">All workloads</a>.";
    if (v.contains("note")) o << " <b>" << html(str(v, "note")) << "</b>";
    o << "</p>";
  }
  o << "</div>\n</div>\n";
  o << "</section>\n";
  return o.str();
}

// ---- cross-validation --------------------------------------------------------------------------

/// The verdict classes of crux diff, in display order, with their colours.
struct VerdictClass {
  const char* key;
  const char* label;
  const char* color;
};
constexpr VerdictClass kVerdicts[] = {
    {"crux_wrong", "crux wrong", "#d7191c"},       {"peer_wrong", "peer wrong", "#fd8d3c"},
    {"error", "error", "#9e4fa5"},                 {"within_tolerance", "within tolerance", "#c2e699"},
    {"agree", "agree", "#1a9641"},                 {"unsupported", "unsupported", "#d9d9d9"},
    {"no_arbiter", "no arbiter", "#f0f0f0"}};

std::string gridHtml(const Json& table) {
  std::vector<std::string> backends;
  std::map<std::string, double> totals;
  for (const auto& [op, perBackend] : table.items())
    for (const auto& [backend, verdicts] : perBackend.items()) {
      if (std::find(backends.begin(), backends.end(), backend) == backends.end()) backends.push_back(backend);
      for (const auto& [verdict, n] : verdicts.items())
        if (n.is_number()) totals[verdict] += n.get<double>();
    }
  const std::vector<std::string> order = {"native", "exact", "fcl", "bullet"};
  std::stable_sort(backends.begin(), backends.end(), [&order](const std::string& a, const std::string& b) {
    return std::find(order.begin(), order.end(), a) - order.begin() < std::find(order.begin(), order.end(), b) - order.begin();
  });
  std::ostringstream o;
  o << "<p class=\"legend\">";
  for (const VerdictClass& k : kVerdicts)
    o << "<span class=\"swatch\" style=\"background:" << k.color << "\"></span>" << k.label << " " << fmt("%.0f", totals[k.key])
      << " &nbsp; ";
  o << "</p>\n<table class=\"grid\"><tr><th>op</th>";
  for (const std::string& b : backends) o << "<th>" << html(backendName(b)) << "</th>";
  o << "</tr>\n";
  for (const auto& [op, perBackend] : table.items()) {
    o << "<tr><td><code>" << html(op) << "</code></td>";
    for (const std::string& b : backends) {
      const Json verdicts = perBackend.value(b, Json::object());
      double total = 0;
      for (const auto& [verdict, n] : verdicts.items())
        if (n.is_number()) total += n.get<double>();
      if (total == 0) {
        o << "<td></td>";
        continue;
      }
      // The cell's colour is its worst class; a bar shows the mix; the counts are spelled out.
      const VerdictClass* worst = nullptr;
      for (const VerdictClass& k : kVerdicts)
        if (!worst && verdicts.value(k.key, 0.0) > 0) worst = &k;
      o << "<td class=\"cell\" style=\"border-left:6px solid " << (worst ? worst->color : "#ffffff") << "\"><div class=\"mix\">";
      for (const VerdictClass& k : kVerdicts) {
        const double n = verdicts.value(k.key, 0.0);
        if (n > 0) o << "<span style=\"width:" << fmt("%.2f", 100 * n / total) << "%;background:" << k.color << "\"></span>";
      }
      o << "</div>";
      std::string text;
      for (const VerdictClass& k : kVerdicts) {
        const double n = verdicts.value(k.key, 0.0);
        if (n > 0) text += (text.empty() ? "" : " &middot; ") + fmt("%.0f ", n) + k.label;
      }
      o << "<small>" << text << "</small></td>";
    }
    o << "</tr>\n";
  }
  o << "</table>\n";
  return o.str();
}

/// A copyable shell line replaying a case through `crux batch`.
std::string reproLine(const Json& lines, const std::string& backend) {
  std::string s = "printf '%s\\n'";
  for (const Json& l : lines) {
    std::string line = l.is_string() ? l.get<std::string>() : l.dump();
    std::string quoted;
    for (const char ch : line) quoted += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    s += " '" + quoted + "'";
  }
  return s + " | crux batch --backend " + backend;
}

std::string findingsHtml(const Json& diff, const Json& corpus, const std::string& corpusHref) {
  std::ostringstream o;
  const Json data = diff.value("data", Json());
  const Json findings = data.is_object() ? data.value("findings", Json::array()) : Json::array();
  // Groups: crux-wrong first, then per backend and cause, biggest first.
  std::map<std::string, std::vector<const Json*>> groups;
  std::map<std::string, double> sizes;
  for (const Json& f : findings) {
    const bool cruxWrong = str(f, "verdict") == "crux_wrong";
    const std::string key = std::string(cruxWrong ? "0" : "1") + "|" + str(f, "backend") + "|" + str(f, "cause");
    groups[key].push_back(&f);
  }
  const Json causes = data.is_object() ? data.value("peer_causes", Json::object()) : Json::object();
  std::vector<std::pair<double, std::string>> order;
  for (const auto& [key, list] : groups) {
    const std::string backend = key.substr(2, key.find('|', 2) - 2), cause = key.substr(key.find('|', 2) + 1);
    const double n = key[0] == '0' ? double(list.size()) : causes.value(backend, Json::object()).value(cause, double(list.size()));
    sizes[key] = n;
    order.emplace_back((key[0] == '0' ? -1e18 : 0) - n, key);
  }
  std::sort(order.begin(), order.end());
  o << "<h3>Disagreements by cause</h3>\n<p>Each group shows up to " << kFindingsShownPerCause << " shrunk cases with a command that replays "
       "it (run it in the build's <code>bin/</code> directory, or with <code>crux</code> on the PATH) and every "
       "backend's answer. Recorded peer disagreements, replayed by CI: <a href=\""
    << html(corpusHref) << "\">oracle/known-peer-disagreements/</a>";
  if (corpus.is_array() && !corpus.empty()) {
    o << " (";
    for (std::size_t i = 0; i < corpus.size(); ++i) o << (i ? ", " : "") << html(scalar(corpus[i]));
    o << ")";
  }
  o << ".</p>\n";
  if (order.empty()) o << "<p>No disagreement beyond tolerance in this run.</p>\n";
  for (const auto& [rank, key] : order) {
    const auto& list = groups[key];
    const Json& f0 = *list.front();
    const bool cruxWrong = key[0] == '0';
    const std::string backend = str(f0, "backend"), cause = str(f0, "cause");
    const bool recorded = corpus.is_array() && std::find(corpus.begin(), corpus.end(), Json(backend + "." + cause + ".jsonl")) != corpus.end();
    o << "<div class=\"finding " << (cruxWrong ? "bad" : "peer") << "\"><h4>" << (cruxWrong ? "CRUX WRONG" : html(backendName(backend)))
      << " &mdash; " << html(cause.empty() ? "crux wrong" : cause) << " <span class=\"note\">" << fmt("%.0f", sizes[key])
      << (sizes[key] == 1 ? " case" : " cases") << (cruxWrong ? " shown" : " in this run") << (recorded ? ", recorded in the corpus" : "")
      << "</span></h4>\n";
    for (std::size_t i = 0; i < list.size() && i < std::size_t(kFindingsShownPerCause); ++i) {
      const Json& f = *list[i];
      o << "<p class=\"note\"><code>" << html(str(f, "op")) << "</code>, family " << html(str(f, "family")) << ", seed "
        << html(scalar(f.value("seed", Json()))) << " case " << html(scalar(f.value("index", Json())))
        << (f.value("exact_grid", false) ? ", integer grid" : "") << "</p>\n";
      if (f.contains("lines") && f["lines"].is_array())
        o << "<pre class=\"repro\">" << html(reproLine(f["lines"], backend)) << "</pre>\n";
      else
        o << "<p class=\"note\">replay: <code>crux batch --backend " << html(backend) << " &lt; raw/diff-cases/"
          << html(str(f, "name")) << ".jsonl</code></p>\n";
      o << "<table class=\"answers\">";
      Json answers = f.value("answers", Json::object());
      if (answers.empty()) {
        if (f.contains("exact")) answers["exact"] = f["exact"];
        if (f.contains(backend)) answers[backend] = f[backend];
      }
      // exact (the arbiter) first, then native, then the peers.
      std::vector<std::string> names;
      for (const char* b : {"exact", "native"})
        if (answers.contains(b)) names.push_back(b);
      for (const auto& [b, a] : answers.items())
        if (b != "exact" && b != "native") names.push_back(b);
      for (const std::string& b : names)
        o << "<tr" << (b == backend ? " class=\"this\"" : "") << "><th>" << html(backendName(b)) << "</th><td><code>"
          << html(answerText(answers[b])) << "</code></td></tr>";
      o << "</table>\n";
    }
    o << "</div>\n";
  }
  return o.str();
}

// ---- tables ------------------------------------------------------------------------------------

std::string ratioCell(const HeadRow& row, const std::string& peer) {
  const Entry* e = row.peer(peer);
  if (!e || !(row.crux.seconds > 0)) return "-";
  return fmt("%.2fx", e->seconds / row.crux.seconds) + (answersDiffer(e->agreement) ? " (answers differ)" : "");
}

std::string sanityLine(const Json& s) {
  if (!s.value("available", false)) return "not available in this build (" + str(s, "reason") + ")";
  if (!s.contains("tests")) return "did not produce results (exit " + scalar(s["exit_status"]) + ")";
  return std::to_string(s["tests"].get<int>() - s["failures"].get<int>()) + " of " + scalar(s["tests"]) +
         " sanity tests pass (native, exact, FCL, Bullet agree on unambiguous cases)";
}

std::string comparisonHtml(const Json& c) {
  std::ostringstream o;
  o << "<section id=\"comparison\"><h2>Compared with the run of " << html(str(c, "old_date")) << "</h2>\n<p>"
    << counted(c, "regressions", "regression") << ", " << counted(c, "improvements", "improvement")
    << " beyond the noise the runs measured (the relative spread, max &minus; min over median, of crux's "
       "and the peer's timed runs, in the old run plus the new; rows whose bench records no runs take the median "
       "noise of their report, marked &ldquo;est.&rdquo;; rows with no noise measured are not flagged).";
  if (!c.value("same_clock", true)) o << " <b>The runs used different bench clocks (old: " << html(str(c, "old_bench_clock")) << ").</b>";
  if (!c.value("same_budget", true)) o << " <b>The runs had different budgets (old: " << html(str(c, "old_budget")) << ").</b>";
  o << "</p>\n";
  // The flagged rows (regressions first) in view, the others folded.
  const std::string header = "<table><tr><th>workload</th><th>figure</th><th>old</th><th>today</th><th>change</th><th>noise</th><th></th></tr>\n";
  std::ostringstream flagged, quiet;
  int quietRows = 0;
  for (const char* pass : {"regression", "improvement", ""})
    for (const Json& r : c["rows"]) {
      const std::string flag = str(r, "flag");
      if (flag != pass) continue;
      const std::string unit = str(r, "value_unit");
      const auto value = [&unit](double v) { return unit == "ratio" ? fmt("%.2fx", v) : valueText(v, unit); };
      std::ostringstream& out = flag.empty() ? quiet : flagged;
      quietRows += flag.empty();
      out << "<tr class=\"" << flag << "\"><td>" << html(str(r, "title")) << "</td><td>" << html(str(r, "what")) << "</td><td>"
          << html(value(num(r, "old"))) << "</td><td>" << html(value(num(r, "new"))) << "</td><td>"
          << fmt("%+.1f%%", 100 * num(r, "change")) << "</td><td>"
          << (r["noise"].is_number() ? fmt("%.1f%%", 100 * num(r, "noise")) + (r.value("noise_measured", false) ? "" : " est.")
                                     : "not measured")
          << "</td><td>" << (flag.empty() ? "" : "<b>" + flag + "</b>") << "</td></tr>\n";
    }
  if (!flagged.str().empty()) o << header << flagged.str() << "</table>\n";
  if (quietRows > 0)
    o << "<details><summary>" << quietRows << " figures within their noise</summary>\n" << header << quiet.str() << "</table></details>\n";
  o << "</section>\n";
  return o.str();
}

std::string targetsHtml(const Json& targets) {
  if (!targets.is_array() || targets.empty()) return "";
  std::ostringstream o;
  o << "<h3>Targets</h3>\n<table><tr><th>target</th><th>measured</th><th>value</th><th>limit</th><th>status</th></tr>\n";
  for (const Json& t : targets)
    o << "<tr><td>" << html(str(t, "target")) << "</td><td>" << html(str(t, "measured")) << "</td><td>"
      << html(scalar(t.value("value", Json()))) << "</td><td>" << html(scalar(t.value("limit", Json()))) << "</td><td>"
      << html(str(t, "status")) << "</td></tr>\n";
  o << "</table>\n";
  return o.str();
}

/// Every scalar of a JSON object as "key: value" rows (libraries, machine).
std::string keyValueTable(const Json& j) {
  std::ostringstream o;
  o << "<table>";
  for (const auto& [k, v] : j.items())
    if (!v.is_object() && !v.is_array()) o << "<tr><th>" << html(k) << "</th><td>" << html(scalar(v)) << "</td></tr>";
  o << "</table>";
  return o.str();
}

const char* kStyle =
    "body{font-family:sans-serif;max-width:1100px;margin:0 auto;padding:0 1em;color:#222;line-height:1.35}"
    "h1{margin:.4em 0 .1em}h2{margin:1.2em 0 .4em;border-bottom:1px solid #ddd}"
    ".machine{color:#555;font-size:13px;margin:.2em 0 .6em}"
    ".cards{display:flex;flex-wrap:wrap;gap:12px}.card{flex:1 1 340px;border:1px solid #ccc;border-radius:6px;"
    "padding:.2em .9em .6em}.card h2{border:0;margin:.4em 0 .2em;font-size:18px}.card.ok{border-left:8px solid #1a9641}"
    ".card.bad{border-left:8px solid #d7191c}.card.unknown{border-left:8px solid #bdbdbd}.big{font-size:17px;font-weight:bold;margin:.3em 0}"
    ".card ul{margin:.2em 0;padding-left:1.2em;font-size:14px}"
    ".note{color:#555;font-size:12.5px}table{border-collapse:collapse;margin:.5em 0;font-size:13px}"
    "td,th{border:1px solid #ccc;padding:2px 6px;text-align:left;vertical-align:top}td.num{text-align:right;white-space:nowrap}.card.perf{flex:1.6 1 540px}"
    "td.win{color:#1a7a35;font-weight:bold;text-align:right}td.loss{color:#b2182b;font-weight:bold;text-align:right}"
    "table.verdict td,table.verdict th{font-size:13.5px}"
    "svg.chart{display:block;margin:1em 0;max-width:100%;height:auto}"
    ".legend{font-size:13px}.swatch{display:inline-block;width:12px;height:12px;margin-right:4px;vertical-align:-1px;"
    "border:1px solid #999}table.grid td.cell{min-width:120px}table.grid small{font-size:11.5px}.mix{display:flex;height:10px;margin:3px 0;"
    "border:1px solid #bbb}.mix span{display:block;height:100%}"
    ".finding{border:1px solid #ddd;border-radius:4px;padding:.1em .7em;margin:.6em 0}.finding.bad{border-color:#d7191c}"
    ".finding h4{margin:.4em 0}pre.repro{background:#f6f6f6;padding:6px;white-space:pre-wrap;word-break:break-all;"
    "user-select:all;font-size:12px}table.answers tr.this th{color:#b2182b}tr.regression td{background:#fde0dd}"
    "tr.improvement td{background:#e5f5e0}"
    "@media print{body{max-width:none}table.grid td.cell{min-width:0}.cards{display:block}.card{margin-bottom:8px}svg.chart,.finding,tr{break-inside:avoid}"
    "*{-webkit-print-color-adjust:exact;print-color-adjust:exact}a{color:inherit}}";

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
                   (bytes ? ": bytes relative to crux's " + valueText(f.entries[0].seconds, "bytes")
                          : ": time relative to " + f.entries[0].label + " (" + valueText(f.entries[0].seconds, "seconds") +
                                " per " + f.unit + ")");
      s["better"] = bytes ? "Bar right of 1: the peer needs more memory (crux is smaller)."
                          : "Bar right of 1: the peer takes longer (crux is faster); left of 1: the peer is faster.";
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
    // Scaling lines: one series per engine, when the sweep has at least two sizes.
    std::set<double> sizes;
    for (const Entry& e : f.sweep) sizes.insert(e.size);
    if (sizes.size() < 2) continue;
    std::vector<std::string> labels;
    for (const Entry& e : f.sweep)
      if (std::find(labels.begin(), labels.end(), e.label) == labels.end()) labels.push_back(e.label);
    for (const std::string& label : labels) {
      const bool bytes = f.valueUnit == "bytes";
      Json s = {{"kind", "line"}, {"chart", base + ".scaling"}, {"workload", workload}, {"name", label},
                {"title", f.bench + ": " + f.title + (bytes ? ": bytes against size" : ": cost against size")},
                {"better", bytes ? "Lower is better; slope = k in bytes ~ n^k (log-log least squares)."
                                 : "Lower is better; slope = the cost growth exponent k in time ~ n^k (log-log least squares)."},
                {"x_label", f.sizeName}, {"y_label", (bytes ? "bytes per " : "time per ") + f.unit}, {"unit", f.valueUnit},
                {"value_unit", f.valueUnit}};
      Json points = Json::array();
      std::string backend;
      for (const Entry& e : f.sweep)
        if (e.label == label && std::isfinite(e.seconds)) {
          points.push_back({{"x", e.size}, {"y", e.seconds}, {"agreement", e.agreement}});
          backend = e.backend;
        }
      if (points.size() < 2) continue;
      s["backends"] = Json::array({backend});
      s["points"] = points;
      s["slope"] = logLogSlope(points);
      series[base + ".scaling." + slug(label)] = s;
    }
  }
  const auto cg = results.find("callgrind");
  if (cg != results.end() && cg->value("available", false)) {
    const Json& b = (*cg)["backends"];
    if (b.contains("crux") && b["crux"].is_object()) {
      Json s = {{"kind", "bar"}, {"chart", "callgrind.rays"}, {"workload", "callgrind/rays"}, {"unit", "ratio"},
                {"title", "callgrind: instructions per ray relative to crux (10k-triangle torus)"},
                {"better", "Bar right of 1: the peer executes more instructions per ray than crux."}};
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
  const Json v = results.contains("verdict") ? results["verdict"] : reportVerdict(results);
  const Json& c = v["correctness"];
  o << "# crux report\n\n" << str(v, "machine") << "; " << str(v, "build") << "; " << str(v, "run") << ".\n\n";
  if (results.value("browser", Json::object()).value("screenshot", "") != "")
    o << "![the verdict, as index.html shows it](verdict.png)\n\n";
  o << "## Is crux right?\n\n**" << cruxWrongText(c).first << "** " << cruxWrongText(c).second << ".\n\n";
  for (const std::string& line : correctnessLines(c)) o << "- " << line << "\n";
  o << "\n## Where is crux faster?\n\n";
  if (v.contains("note")) o << "**" << str(v, "note") << "**\n\n";
  const Json& perf = v["performance"];
  if (perf.empty()) {
    o << "No timed workload with a peer in this build.\n";
  } else {
    o << "| peer | crux faster | crux slower | geometric mean of peer / crux time | worst row for crux |\n|---|---|---|---|---|\n";
    for (const Json& p : perf) {
      o << "| " << str(p, "name") << " | " << count(p, "crux_faster") << " of " << count(p, "workloads") << " | "
        << count(p, "crux_slower") << " of " << count(p, "workloads") << " | " << (p["geomean"].is_number() ? fmt("%.2fx", num(p, "geomean")) : "-") << " | ";
      if (p["worst"].is_object()) o << worstText(p) << fmt("%.2fx", num(p["worst"], "ratio"));
      if (num(p, "answers_differ") > 0) o << " (" << count(p, "answers_differ") << " more with different answers, not counted)";
      o << " |\n";
    }
  }
  if (results.contains("comparison")) {
    const Json& cmp = results["comparison"];
    o << "\n## Compared with the run of " << str(cmp, "old_date") << "\n\n" << counted(cmp, "regressions", "regression") << ", "
      << counted(cmp, "improvements", "improvement") << " beyond the measured noise (index.html lists every row).\n\n";
    for (const Json& r : cmp["rows"])
      if (!str(r, "flag").empty()) {
        const std::string unit = str(r, "value_unit");
        const auto value = [&unit](double x) { return unit == "ratio" ? fmt("%.2fx", x) : valueText(x, unit); };
        o << "- **" << str(r, "flag") << "**: " << str(r, "title") << ", " << str(r, "what") << ": " << value(num(r, "old"))
          << " -> " << value(num(r, "new")) << " (" << fmt("%+.1f%%", 100 * num(r, "change")) << ", noise "
          << fmt("%.1f%%", 100 * num(r, "noise")) << ")\n";
      }
  }
  o << "\n## All workloads (peer time / crux time: > 1 means crux is faster)\n\n";
  std::vector<std::string> peers;
  const std::vector<HeadRow> rows = headRows(results, &peers);
  o << "| workload | input | crux |";
  for (const std::string& p : peers) o << " " << backendName(p) << " |";
  o << "\n|---|---|---|";
  for (std::size_t i = 0; i < peers.size(); ++i) o << "---|";
  o << "\n";
  for (const HeadRow& row : rows) {
    o << "| " << row.title << " | " << row.input << " | " << valueText(row.crux.seconds, row.valueUnit) << "/" << row.unit << " |";
    for (const std::string& p : peers) o << " " << ratioCell(row, p) << " |";
    o << "\n";
  }
  o << "\nAnswers are compared on every query before timing; \"answers differ\" marks a peer that disagreed "
       "(see the bench logs in raw/). Memory rows: peer bytes / crux bytes (> 1: crux is smaller).\n";
  const Json benches = results.value("benches", Json::object());
  for (const auto& [bench, step] : benches.items())
    if (!step.value("available", false)) o << "\n- " << bench << ": not available in this build";
  o << "\n";
  return o.str();
}

std::string renderHtml(const nlohmann::json& results) {
  std::ostringstream o;
  const Json v = results.contains("verdict") ? results["verdict"] : reportVerdict(results);
  o << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
       "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>crux report</title>\n<style>"
    << kStyle << "</style></head><body>\n";
  o << verdictHtml(v);
  o << "<p class=\"note\">Contents: <a href=\"#cross-validation\">cross-validation</a> &middot; "
    << (results.contains("comparison") ? "<a href=\"#comparison\">comparison</a> &middot; " : "")
    << "<a href=\"#workloads\">all workloads</a> &middot; per bench charts &middot; <a href=\"#machine\">machine and "
       "libraries</a>. Raw figures: <a href=\"results.json\">results.json</a>; terminal summary: <a "
       "href=\"summary.md\">summary.md</a>.</p>\n";
  if (results.contains("comparison")) o << comparisonHtml(results["comparison"]);

  const Json cross = results.value("cross_validation", Json::object());
  const Json sanity = cross.value("sanity", Json::object());
  const Json diff = cross.value("diff", Json::object());
  o << "<section id=\"cross-validation\"><h2>Cross-validation</h2>\n<p>Oracle sanity suite: " << html(sanityLine(sanity))
    << ".";
  if (sanity.contains("cases")) {
    std::string failed;
    for (const Json& t : sanity["cases"])
      if (!t.value("passed", false)) failed += (failed.empty() ? "" : ", ") + str(t, "name");
    if (!failed.empty()) o << " <b>Failed: " << html(failed) << "</b>.";
  }
  o << "</p>\n";
  const Json data = diff.value("data", Json());
  if (!diff.value("available", false)) {
    o << "<p>crux diff: " << html(str(diff, "reason")) << "</p>\n";
  } else if (!data.is_object() || !data.contains("table")) {
    o << "<p>crux diff wrote no summary (exit " << html(scalar(diff.value("exit_status", Json()))) << ").</p>\n";
  } else {
    o << "<p><code>crux diff</code> answered " << count(data, "cases") << " generated cases on every backend and judged each "
      << "answer against the exact (CGAL) backend; per op and backend:</p>\n"
      << gridHtml(data["table"]) << "<p class=\"note\">command: <code>" << html(str(diff, "command")) << "</code></p>\n";
    const std::string corpusHref = "file://" + str(results.value("report", Json::object()), "source_dir") +
                                   "/oracle/known-peer-disagreements/";
    o << findingsHtml(diff, cross.value("known_peer_disagreements", Json::array()), corpusHref);
  }
  o << "</section>\n";

  o << "<section id=\"workloads\"><h2>All workloads (peer time / crux time: &gt; 1 means crux is faster)</h2>\n";
  std::vector<std::string> peers;
  const std::vector<HeadRow> rows = headRows(results, &peers);
  o << "<table><tr><th>workload</th><th>input</th><th>crux</th>";
  for (const std::string& p : peers) o << "<th>" << html(backendName(p)) << "</th>";
  o << "</tr>\n";
  for (const HeadRow& row : rows) {
    o << "<tr><td>" << html(row.title) << "</td><td>" << html(row.input) << "</td><td>"
      << html(valueText(row.crux.seconds, row.valueUnit) + "/" + row.unit) << "</td>";
    for (const std::string& p : peers) {
      const Entry* e = row.peer(p);
      const bool win = e && row.crux.seconds > 0 && e->seconds > row.crux.seconds;
      o << "<td class=\"" << (e ? (win ? "win" : "loss") : "num") << "\">" << html(ratioCell(row, p)) << "</td>";
    }
    o << "</tr>\n";
  }
  o << "</table></section>\n";

  const Json series = results.value("series", Json::object());
  const Json benches = results.value("benches", Json::object());
  for (const auto& [bench, step] : benches.items()) {
    o << "<section class=\"bench\"><h2 id=\"" << html(bench) << "\">" << html(bench) << "</h2>\n";
    if (!step.value("available", false)) {
      o << "<p>not available in this build: " << html(str(step, "reason")) << "</p></section>\n";
      continue;
    }
    o << "<p class=\"note\"><code>" << html(str(step, "command")) << "</code>: exit " << html(scalar(step["exit_status"]))
      << ", " << fmt("%.1f", num(step, "seconds")) << " s; log <a href=\"" << html(str(step, "log")) << "\">"
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
      o << (str(*m.front().second, "kind") == "bar" ? barChart(m.front().first, *m.front().second) : lineChart(m));
    }
    // Table of times per workload.
    const Json benchData = step.value("data", Json());
    std::vector<WorkloadFigures> mine;
    for (const WorkloadFigures& f : figures(results))
      if (f.bench == bench) mine.push_back(f);
    if (!mine.empty()) o << "<details><summary>Every engine's figures (tables)</summary>\n";
    for (const WorkloadFigures& f : mine) {
      o << "<h3>" << html(f.title) << "</h3>\n<table><tr><th>engine</th>" << (f.sizeName.empty() ? "" : "<th>" + f.sizeName + "</th>")
        << "<th>" << (f.valueUnit == "bytes" ? "bytes" : "time") << " per " << html(f.unit) << "</th><th>vs crux</th><th>answers</th></tr>\n";
      const std::vector<Entry>& entries = f.sweep.empty() ? f.entries : f.sweep;
      std::map<double, double> cruxAt;
      for (const Entry& e : entries)
        if (e.backend == "crux" && !cruxAt.count(e.size)) cruxAt[e.size] = e.seconds;
      for (const Entry& e : entries) {
        const double ref = cruxAt.count(e.size) ? cruxAt[e.size] : std::nan("");
        o << "<tr><td>" << html(e.label) << "</td>" << (f.sizeName.empty() ? "" : "<td>" + fmt("%.0f", e.size) + "</td>")
          << "<td>" << html(valueText(e.seconds, f.valueUnit)) << "</td><td>" << (ref > 0 ? fmt("%.2fx", e.seconds / ref) : "")
          << "</td><td>" << html(e.agreement) << "</td></tr>\n";
      }
      o << "</table>\n";
    }
    if (!mine.empty()) o << "</details>\n";
    if (benchData.is_object()) o << targetsHtml(benchData.value("targets", Json()));
    if (mine.empty() && benchData.is_object())
      o << "<p>This bench's figures have a format the report does not read: see <a href=\"results.json\">results.json</a>.</p>\n";
    if (step.contains("text")) o << "<p>(no JSON output: its printed tables)</p><pre>" << html(str(step, "text")) << "</pre>\n";
    o << "</section>\n";
  }
  const auto cg = results.find("callgrind");
  if (cg != results.end()) {
    o << "<section><h2>callgrind</h2>\n";
    if (series.contains("callgrind.rays")) o << barChart("callgrind.rays", series["callgrind.rays"]);
    if (cg->value("available", false)) {
      o << "<p class=\"note\">" << html(str(*cg, "workload")) << "</p>\n<table><tr><th>backend</th><th>instructions per ray</th></tr>";
      const Json backends = cg->value("backends", Json::object());
      for (const auto& [name, b] : backends.items())
        o << "<tr><td>" << html(name) << "</td><td>" << (b.is_object() ? fmt("%.0f", num(b, "instructions_per_ray")) : "failed")
          << "</td></tr>";
      o << "</table>\n";
    } else {
      o << "<p>" << html(str(*cg, "reason")) << "</p>\n";
    }
    o << "</section>\n";
  }
  const Json machine = results.value("machine", Json::object());
  o << "<section id=\"machine\"><h2>Machine and libraries</h2>\n" << keyValueTable(machine);
  if (machine.contains("libraries")) o << "<h3>Libraries</h3>\n" << keyValueTable(machine["libraries"]);
  o << "</section>\n</body></html>\n";
  return o.str();
}

}  // namespace crux::cli
