// The page of a search (tune.html): the objective of each trial with the best so far drawn
// over it, the trials that broke a constraint marked apart, every trial as a row, and the
// validation. One file, no script: it opens from disk and prints as it shows.

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "overtake/base/text.hpp"
#include "overtake/batch/tune.hpp"
#include "overtake/eval/compare.hpp"

namespace overtake::batch {
namespace {

using base::fixed_text;

std::string html(std::string_view text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string num(double v) {
  return fixed_text(v, 1);
}

// A chart's frame: its size and margins, and the objective's range along y.
struct Frame {
  double w, h, left, right, top, bottom;
  double lo, hi;  ///< the objective's range, padded
  [[nodiscard]] double y(double v) const { return top + (h - top - bottom) * (hi - v) / (hi - lo); }
};

// The frame of objective values in [lo, hi] (a point widened to 1, then 8% each side).
Frame frame_of(double w, double h, double lo, double hi) {
  if (hi - lo < 1e-9) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double pad = (hi - lo) * 0.08;
  return {w, h, 60, 20, 20, 50, lo - pad, hi + pad};
}

// The SVG's opening, its plot area and the objective's ticks along y.
std::string open_svg(const Frame& f, const std::string& label) {
  std::string s = "<svg xmlns='http://www.w3.org/2000/svg' width='" + num(f.w) + "' height='" +
                  num(f.h) + "' role='img' aria-label='" + label + "'>\n";
  s += "<rect x='" + num(f.left) + "' y='" + num(f.top) + "' width='" +
       num(f.w - f.left - f.right) + "' height='" + num(f.h - f.top - f.bottom) +
       "' fill='#fafafa' stroke='#ccc'/>\n";
  for (int k = 0; k <= 4; ++k) {
    const double v = f.lo + (f.hi - f.lo) * k / 4.0;
    s += "<text x='" + num(f.left - 6) + "' y='" + num(f.y(v) + 4) +
         "' text-anchor='end' font-size='11'>" + fixed_text(v, 2) + "</text>\n";
  }
  return s;
}

// The chart: trials along x, the objective along y; feasible trials as dots, the best so far
// as a step line, the others as crosses under the axis.
std::string chart(const TuneSpec& spec, const TuneOutcome& o) {
  const bool higher = tune_figure_higher_is_better(spec.objective);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& t : o.trials) {
    if (!t.feasible) continue;
    lo = std::min(lo, t.objective);
    hi = std::max(hi, t.objective);
  }
  if (!std::isfinite(lo)) {
    lo = 0;
    hi = 1;
  }
  const Frame f = frame_of(760, 280, lo, hi);
  const double kH = f.h, kLeft = f.left, kBottom = f.bottom;
  const double n = std::max<double>(1.0, static_cast<double>(o.trials.size()));
  const auto sx = [&](double trial) {
    return kLeft + (f.w - kLeft - f.right) * (n <= 1 ? 0.5 : (trial - 1) / (n - 1));
  };
  const auto sy = [&](double v) { return f.y(v); };
  std::string s = open_svg(f, "objective per trial");
  s += "<text x='" + num(kLeft) + "' y='" + num(kH - 8) + "' font-size='12'>trial 1 … " +
       std::to_string(o.trials.size()) + " · " + html(spec.objective) +
       " (dots: trials that met the constraints; line: best so far; red crosses: broke "
       "one)</text>\n";
  std::string line;
  std::optional<double> best;
  for (const auto& t : o.trials) {
    const double x = sx(t.number);
    if (t.feasible) {
      if (!best || (higher ? t.objective > *best : t.objective < *best)) best = t.objective;
      s += "<circle cx='" + num(x) + "' cy='" + num(sy(t.objective)) +
           "' r='3.5' fill='#1f77b4'><title>trial " + std::to_string(t.number) + ": " +
           fixed_text(t.objective, 3) + "</title></circle>\n";
    } else {
      const double y = kH - kBottom + 12;
      s += "<path d='M" + num(x - 4) + " " + num(y - 4) +
           "l8 8m0 -8l-8 8' stroke='#d62728' "
           "stroke-width='2'><title>trial " +
           std::to_string(t.number) + ": " +
           html(t.violations.empty() ? "" : t.violations.front()) + "</title></path>\n";
    }
    if (best) line += (line.empty() ? "M" : " L") + num(x) + " " + num(sy(*best));
  }
  if (!line.empty()) {
    s += "<path d='" + line + "' fill='none' stroke='#2ca02c' stroke-width='2'/>\n";
  }
  return s + "</svg>\n";
}

// A trial's risk figure, when it has one.
std::optional<double> figure(const TuneTrial& t, const char* name) {
  const auto it = t.figures.find(name);
  if (it == t.figures.end() || !it->is_number()) return std::nullopt;
  return it->get<double>();
}

// The trials on the plane users choose on: the risk along x (log; a trial with no event at
// its interval's upper end, hollow), the objective along y; the Pareto set (no other trial
// both better in the objective and lower in risk) joined, --max-risk as a dashed line.
std::string risk_plane(const TuneSpec& spec, const TuneOutcome& o) {
  const bool higher = tune_figure_higher_is_better(spec.objective);
  struct Point {
    const TuneTrial* t;
    double risk;  // the estimate, or the upper end with no event
    bool bound;
  };
  std::vector<Point> points;
  for (const auto& t : o.trials) {
    const auto r = figure(t, "risk_per_100mi");
    const auto hi = figure(t, "risk_high_per_100mi");
    if (!r || !hi || !std::isfinite(t.objective)) continue;
    const bool bound = *r <= 0.0;
    points.push_back({&t, bound ? *hi : *r, bound});
  }
  if (points.empty()) return "<p>No trial has a risk estimate yet.</p>\n";
  double rlo = std::numeric_limits<double>::infinity(), rhi = 0.0;
  double lo = rlo, hi = -rlo;
  for (const auto& p : points) {
    rlo = std::min(rlo, std::max(p.risk, 1e-6));
    rhi = std::max(rhi, p.risk);
    lo = std::min(lo, p.t->objective);
    hi = std::max(hi, p.t->objective);
  }
  if (spec.risk->max_per_100mi && *spec.risk->max_per_100mi > 0.0) {
    rlo = std::min(rlo, *spec.risk->max_per_100mi);
    rhi = std::max(rhi, *spec.risk->max_per_100mi);
  }
  const double llo = std::floor(std::log10(rlo)),
               lhi = std::max(llo + 1, std::ceil(std::log10(rhi)));
  const Frame f = frame_of(760, 320, lo, hi);
  const double kH = f.h, kLeft = f.left, kTop = f.top, kBottom = f.bottom;
  const auto sx = [&](double r) {
    return kLeft + (f.w - kLeft - f.right) * (std::log10(std::max(r, 1e-6)) - llo) / (lhi - llo);
  };
  const auto sy = [&](double v) { return f.y(v); };
  std::string s = open_svg(f, "objective against risk");
  for (double d = llo; d <= lhi + 1e-9; d += 1.0) {
    s += "<text x='" + num(sx(std::pow(10.0, d))) + "' y='" + num(kH - kBottom + 16) +
         "' text-anchor='middle' font-size='11'>" + base::shortest_text(std::pow(10.0, d)) +
         "</text>\n";
  }
  s += "<text x='" + num(kLeft) + "' y='" + num(kH - 8) + "' font-size='12'>" +
       html(spec.risk->event.name()) + " per 100 mi (log; hollow: no event, at the interval's " +
       "upper end) · " + html(spec.objective) + " · line: the Pareto set</text>\n";
  if (const auto limit = spec.risk->max_per_100mi; limit && *limit > 0.0) {
    s += "<line x1='" + num(sx(*limit)) + "' x2='" + num(sx(*limit)) + "' y1='" + num(kTop) +
         "' y2='" + num(kH - kBottom) +
         "' stroke='#d62728' stroke-dasharray='5 4'><title>--max-risk " +
         base::shortest_text(*limit) + "</title></line>\n";
  }
  // The Pareto set, by risk: each point no other is at least as good in both and better in one.
  const auto better = [&](double a, double b) { return higher ? a > b : a < b; };
  std::vector<const Point*> front;
  for (const auto& p : points) {
    const bool dominated = std::any_of(points.begin(), points.end(), [&](const Point& q) {
      return q.risk <= p.risk && !better(p.t->objective, q.t->objective) &&
             (q.risk < p.risk || better(q.t->objective, p.t->objective));
    });
    if (!dominated) front.push_back(&p);
  }
  std::sort(front.begin(), front.end(),
            [](const Point* a, const Point* b) { return a->risk < b->risk; });
  std::string line;
  for (const Point* p : front) {
    line += (line.empty() ? "M" : " L") + num(sx(p->risk)) + " " + num(sy(p->t->objective));
  }
  s += "<path d='" + line + "' fill='none' stroke='#2ca02c' stroke-width='2'/>\n";
  for (const auto& p : points) {
    const bool best = o.best && *o.best == p.t->number;
    const std::string colour = !p.t->feasible ? "#d62728" : best ? "#2ca02c" : "#1f77b4";
    s += "<circle cx='" + num(sx(p.risk)) + "' cy='" + num(sy(p.t->objective)) + "' r='" +
         (best ? "5.5" : "3.5") + "' " +
         (p.bound ? "fill='none' stroke='" + colour + "' stroke-width='1.5'"
                  : "fill='" + colour + "'") +
         "><title>trial " + std::to_string(p.t->number) + ": " + fixed_text(p.t->objective, 3) +
         ", " + (p.bound ? "no event, at most " : "") + fixed_text(p.risk, 3) +
         " per 100 mi</title></circle>\n";
  }
  return s + "</svg>\n";
}

}  // namespace

std::string tune_page(const TuneSpec& spec, const TuneOutcome& o) {
  std::string s =
      "<!doctype html>\n<html lang='en'><head><meta charset='utf-8'><title>overtake tune: " +
      html(spec.policy) +
      "</title>\n<style>body{font:14px system-ui,sans-serif;margin:2em;max-width:60em}"
      "table{border-collapse:collapse}td,th{border:1px solid #ddd;padding:2px 8px;"
      "text-align:right}tr.best{background:#e8f5e9}tr.broke{color:#a00}"
      "pre{background:#f6f6f6;padding:1em;overflow:auto}</style></head><body>\n";
  s += "<h1>overtake tune: " + html(spec.policy) + "</h1>\n<p>" + std::to_string(o.trials.size()) +
       " trials of " + std::to_string(spec.trials) + " (" + html(spec.algorithm) +
       "), each a bench of " + std::to_string(spec.seeds.size()) + " training seeds × " +
       fixed_text(spec.minutes, 1) + " min" +
       (spec.maps.size() > 1 ? " on each of " + std::to_string(spec.maps.size()) + " maps" : "") +
       "; ended by " + html(o.stop_reason) + ".</p>\n";
  s += chart(spec, o);
  if (spec.risk) {
    s += "<h2>Speed against risk</h2>\n" + risk_plane(spec, o);
  }
  if (!o.validations.empty()) s += "<h2>Validation on held-out seeds</h2>\n";
  for (const TuneValidation& v : o.validations) {
    if (o.validations.size() > 1) s += "<h3>On " + html(v.map) + "</h3>\n";
    s += "<p><b>" + html(v.verdict) + "</b></p>\n<pre>" + html(eval::compare_text(v.comparison)) +
         "</pre>\n";
    if (!v.risk_verdict.empty()) s += "<p><b>" + html(v.risk_verdict) + "</b></p>\n";
  }
  s += "<h2>Trials</h2>\n<table><tr><th>trial</th>";
  for (const auto& p : spec.params) s += "<th>" + html(p.name) + "</th>";
  s += "<th>" + html(spec.objective) + "</th>" +
       (spec.risk ? "<th>" + html(spec.risk->event.name()) + " per 100 mi</th>" : "") +
       "<th>constraints</th></tr>\n";
  for (const auto& t : o.trials) {
    const bool is_best = o.best && *o.best == t.number;
    s += std::string("<tr") +
         (is_best       ? " class='best'"
          : !t.feasible ? " class='broke'"
                        : "") +
         "><td>" + std::to_string(t.number) + "</td>";
    for (const auto& p : spec.params) s += "<td>" + fixed_text(t.params.at(p.name), 4) + "</td>";
    s += "<td>" + (std::isfinite(t.objective) ? fixed_text(t.objective, 3) : std::string("-")) +
         "</td><td>";
    if (spec.risk) {
      const auto r = figure(t, "risk_per_100mi");
      const auto rl = figure(t, "risk_low_per_100mi");
      const auto rh = figure(t, "risk_high_per_100mi");
      s += (r && rl && rh
                ? fixed_text(*r, 3) + " (" + fixed_text(*rl, 3) + "–" + fixed_text(*rh, 3) + ")"
                : std::string("-")) +
           "</td><td>";
    }
    std::string v;
    for (const auto& w : t.violations) v += (v.empty() ? "" : "; ") + w;
    s += html(t.feasible ? std::string("met") : v) + "</td></tr>\n";
  }
  return s + "</table>\n</body></html>\n";
}

}  // namespace overtake::batch
