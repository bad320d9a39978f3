#include "analysis/study.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>

#include "analysis/text.hpp"
#include "core/fnv.hpp"

namespace penumbra::study {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

std::string percent(double v) {
  if (!std::isfinite(v)) return "n/a";
  return format(v < 0.001 ? "%.3f%%" : v < 0.1 ? "%.2f%%" : "%.1f%%", 100 * v);
}

std::vector<Row> curve_rows(const std::vector<Row>& rows, const std::string& curve) {
  std::vector<Row> out;
  for (const Row& r : rows)
    if (r.curve == curve) out.push_back(r);
  std::sort(out.begin(), out.end(),
            [](const Row& a, const Row& b) { return a.samples < b.samples; });
  return out;
}

}  // namespace

std::vector<Run> default_runs(int bounces, int max_spp, bool quick) {
  std::vector<Run> runs;
  RenderOptions base;
  base.bounces = bounces;
  for (bool nee : {false, true})
    for (int spp = 1; spp <= max_spp; spp *= 4) {
      if (quick && spp > 16) break;
      RenderOptions o = base;
      o.method = Method::pt;
      o.pt.spp = spp;
      o.pt.nee = nee;
      std::string label = nee ? "pt --nee " : "pt ";
      label += std::to_string(spp);
      label += " spp";
      runs.push_back({label, nee ? "pt nee" : "pt", o});
    }
  auto rc = [&](const std::string& label, auto&& set) {
    RenderOptions o = base;
    set(o.rc);
    runs.push_back({label, "", o});
  };
  auto hrc = [&](const std::string& label, auto&& set) {
    RenderOptions o = base;
    o.method = Method::hrc;
    set(o.hrc);
    runs.push_back({label, "", o});
  };
  rc("rc (defaults)", [](RcOptions&) {});
  rc("rc --fix none", [](RcOptions& r) { r.fix = MergeFix::none; });
  hrc("hrc (defaults)", [](HrcOptions&) {});
  if (quick) return runs;
  hrc("hrc --no-cross-blur", [](HrcOptions& h) { h.cross_blur = false; });
  hrc("hrc --blur-near-segment", [](HrcOptions& h) { h.blur_near = true; });
  hrc("hrc --corners walls", [](HrcOptions& h) { h.corners = Corners::walls; });
  hrc("hrc --no-near-segment", [](HrcOptions& h) { h.near_segment = false; });
  hrc("hrc --storage f16", [](HrcOptions& h) { h.storage = Storage::f16; });
  hrc("hrc --wall-fan 0", [](HrcOptions& h) { h.wall_fan = 0; });
  hrc("hrc --fan-share 0.00390625", [](HrcOptions& h) { h.fan_share = 1.0f / 256; });
  hrc("hrc --fan-share 0.0625", [](HrcOptions& h) { h.fan_share = 1.0f / 16; });
  hrc("hrc --near-fan 0", [](HrcOptions& h) { h.near_fan = 0; });
  hrc("hrc --wall-fan 4 --near-fan 8", [](HrcOptions& h) { h.wall_fan = 4, h.near_fan = 8; });
  hrc("hrc --even-weight 0.5", [](HrcOptions& h) { h.even_weight = 0.5f; });
  rc("rc --fix nearest", [](RcOptions& r) { r.fix = MergeFix::nearest; });
  rc("rc --interval 2", [](RcOptions& r) { r.interval = 2; });
  rc("rc --directions 8", [](RcOptions& r) { r.directions = 8; });
  rc("rc --probe-spacing 2", [](RcOptions& r) { r.probe_spacing = 2; });
  rc("rc --preaverage", [](RcOptions& r) { r.preaverage = true; });
  return runs;
}

double equal_error_time(const std::vector<Row>& curve, double e, bool& extrapolated) {
  extrapolated = false;
  if (curve.size() < 2 || !(e > 0)) return kNaN;
  // The segment whose error range holds e; else the end segment on e's side (the curve runs
  // from fast and noisy to slow and accurate).
  std::size_t k = 0;
  bool found = false;
  for (std::size_t i = 0; i + 1 < curve.size() && !found; ++i) {
    const double a = curve[i].error.relative_rmse, b = curve[i + 1].error.relative_rmse;
    if (e <= std::max(a, b) && e >= std::min(a, b)) k = i, found = true;
  }
  if (!found) {
    extrapolated = true;
    k = e < curve.back().error.relative_rmse ? curve.size() - 2 : 0;
  }
  const double x0 = std::log(curve[k].time_ms), x1 = std::log(curve[k + 1].time_ms);
  const double y0 = std::log(curve[k].error.relative_rmse),
               y1 = std::log(curve[k + 1].error.relative_rmse);
  if (y1 == y0) return curve[k].time_ms;
  return std::exp(x0 + (std::log(e) - y0) * (x1 - x0) / (y1 - y0));
}

void add_equal_error_times(std::vector<Row>& rows) {
  const std::vector<Row> curve = curve_rows(rows, "pt nee");
  for (Row& r : rows)
    r.pt_equal_time_ms = equal_error_time(curve, r.error.relative_rmse, r.extrapolated);
}

double convergence_order(const std::vector<Row>& rows, const std::string& curve) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (const Row& r : rows) {
    if (r.curve != curve || r.samples == 0 || !(r.error.relative_rmse > 0)) continue;
    const double x = std::log(double(r.samples)), y = std::log(r.error.relative_rmse);
    sx += x, sy += y, sxx += x * x, sxy += x * y, ++n;
  }
  if (n < 2 || n * sxx == sx * sx) return kNaN;
  return -(n * sxy - sx * sy) / (n * sxx - sx * sx);
}

std::string to_csv(const std::vector<Row>& rows) {
  std::ostringstream s;
  s << "label,curve,method,spp,time_ms,rmse,relative_rmse,mean_abs,max_abs,psnr,bias,"
       "pt_equal_time_ms,extrapolated\n";
  for (const Row& r : rows) {
    char buf[512];
    std::snprintf(buf, sizeof buf, "\"%s\",%s,%s,%llu,%.3f,%.6g,%.6g,%.6g,%.6g,%.4f,%.6g,%.3f,%d\n",
                  r.label.c_str(), r.curve.c_str(), r.method.c_str(), (unsigned long long)r.samples,
                  r.time_ms, r.error.rmse, r.error.relative_rmse, r.error.mean_abs, r.error.max_abs,
                  r.error.psnr, r.error.bias, r.pt_equal_time_ms, r.extrapolated ? 1 : 0);
    s << buf;
  }
  return s.str();
}

std::string to_markdown(const std::vector<Row>& rows, const std::string& scene,
                        const Reference& ref) {
  std::ostringstream s;
  s << "Scene `" << scene << "`; reference: path tracer with NEE, " << ref.spp << " samples per "
    << ref.unit << " (`" << ref.path << "`), its own relative RMSE estimated at "
    << percent(ref.estimated_rel) << " by extrapolating the NEE curve.\n\n";
  s << "| configuration | time (ms) | rel. RMSE | PSNR (dB) | bias | max abs. error "
       "| PT+NEE time at equal error (ms) | speed-up |\n";
  s << "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const Row& r : rows) {
    const bool has = std::isfinite(r.pt_equal_time_ms);
    std::string equal = "n/a";
    if (has) {
      equal = r.extrapolated ? "~" : "";
      equal += format("%.0f", r.pt_equal_time_ms);
    }
    s << "| " << r.label << " | " << format("%.0f", r.time_ms) << " | "
      << percent(r.error.relative_rmse) << " | " << format("%.1f", r.error.psnr) << " | "
      << format("%+.3g", r.error.bias) << " | " << format("%.3g", r.error.max_abs) << " | " << equal
      << " | " << (has ? format("%.2gx", r.pt_equal_time_ms / r.time_ms) : "n/a") << " |\n";
  }
  // The fitted orders of the curves there are (3D has only the NEE one).
  std::string fits;
  for (const auto& [curve, name] : {std::pair{"pt", " plain"}, std::pair{"pt nee", " with NEE"}}) {
    const double k = convergence_order(rows, curve);
    if (!std::isfinite(k)) continue;
    fits += fits.empty() ? "k = " : ", ";
    fits += format("%.2f", k) + name;
  }
  if (!fits.empty())
    s << "\nPath tracer convergence (fitted error ~ spp^-k): " << fits
      << " (k = 0.5 is the Monte Carlo rate).\n";
  return s.str();
}

Expected<std::string> splice_section(const std::string& doc, const std::string& name,
                                     const std::string& body) {
  const std::string open = "<!-- bench-quality " + name + " -->",
                    close = "<!-- /bench-quality " + name + " -->";
  const std::size_t a = doc.find(open);
  if (a == std::string::npos)
    return Error{"no line `" + open + "` marks where the study of " + name + " goes"};
  if (doc.find(open, a + open.size()) != std::string::npos)
    return Error{"the marker `" + open + "` appears twice"};
  const std::size_t b = doc.find(close, a);
  if (b == std::string::npos) return Error{"no line `" + close + "` after `" + open + "`"};
  std::string out = doc.substr(0, a + open.size()) + "\n";
  out += body;
  if (!body.empty() && body.back() != '\n') out += '\n';
  return out + doc.substr(b);
}

namespace {

// Where a plot puts things: log-log axes over whole decades that hold every row, the curves and
// the single points with a legend column on the right. Shared by the SVG and the PNG.
struct Plot {
  static constexpr double left = 70, top = 40, bottom = 50, frame = 480;
  static constexpr double legend_gap = 36;   // frame to legend: room for the last time label
  static constexpr double legend_step = 26;  // pixels per legend line (text 2x and a gap)
  double H = 480;                            // taller when the legend needs it
  double right = 230;                        // the legend column, as wide as its longest name needs
  double x0 = 0, x1 = 1, y0 = -2, y1 = 0;
  double W() const { return left + frame + right; }
  double frame_right() const { return left + frame; }
  double px(double t) const { return left + (std::log10(t) - x0) / (x1 - x0) * frame; }
  double py(double e) const { return top + (y1 - std::log10(e)) / (y1 - y0) * (H - top - bottom); }
  struct Series {
    std::string name, colour;
    bool line;
    std::vector<std::pair<double, double>> points;  // pixel positions
    std::string tag;  // a single point's number, drawn beside it and before its legend name
  };
  std::vector<Series> series;
};

bool plottable(const Row& r) {
  return r.time_ms > 0 && r.error.relative_rmse > 0;
}

Plot layout(const std::vector<Row>& rows) {
  Plot p;
  double tmin = INFINITY, tmax = 0, emin = INFINITY, emax = 0;
  for (const Row& r : rows) {
    if (!plottable(r)) continue;
    tmin = std::min(tmin, r.time_ms), tmax = std::max(tmax, r.time_ms);
    emin = std::min(emin, r.error.relative_rmse), emax = std::max(emax, r.error.relative_rmse);
  }
  if (!(tmax > 0)) tmin = 1, tmax = 10, emin = 0.01, emax = 1;
  p.x0 = std::floor(std::log10(tmin)), p.x1 = std::max(p.x0 + 1, std::ceil(std::log10(tmax)));
  p.y0 = std::floor(std::log10(emin)), p.y1 = std::max(p.y0 + 1, std::ceil(std::log10(emax)));
  // The legend first: the plot grows downwards when it is longer than the frame, and the
  // positions depend on the height.
  const std::pair<const char*, const char*> curves[] = {{"pt", "#1f77b4"}, {"pt nee", "#ff7f0e"}};
  const char* names[] = {"path tracer", "path tracer + NEE"};
  std::vector<std::pair<const Row*, std::vector<Row>>> entries;  // a single row, or a curve
  std::vector<int> curve_of;
  for (int c = 0; c < 2; ++c) {
    std::vector<Row> curve;
    for (const Row& r : curve_rows(rows, curves[c].first))
      if (plottable(r)) curve.push_back(r);
    if (!curve.empty()) entries.push_back({nullptr, curve}), curve_of.push_back(c);
  }
  for (const Row& r : rows)
    if (r.curve.empty() && plottable(r)) entries.push_back({&r, {}}), curve_of.push_back(-1);
  p.H = std::max(p.H, p.top + 10 + p.legend_step * double(entries.size()) + 10);
  // Single points are numbered: with more of them than colours, the number tells them apart.
  static const char* palette[] = {"#2ca02c", "#d62728", "#9467bd", "#8c564b",
                                  "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  int k = 0;
  for (std::size_t e = 0; e < entries.size(); ++e) {
    const int c = curve_of[e];
    if (c >= 0) {
      Plot::Series s{names[c], curves[c].second, true, {}, ""};
      for (const Row& r : entries[e].second)
        s.points.push_back({p.px(r.time_ms), p.py(r.error.relative_rmse)});
      p.series.push_back(s);
    } else {
      const Row& r = *entries[e].first;
      const std::string tag = std::to_string(k + 1);
      p.series.push_back({tag + " " + r.label,
                          palette[k++ % 8],
                          false,
                          {{p.px(r.time_ms), p.py(r.error.relative_rmse)}},
                          tag});
    }
  }
  // The legend column widens to its longest name (at least the NEE curve's).
  int longest = analysis::text_width(names[1], 2);
  for (const Plot::Series& c : p.series)
    longest = std::max(longest, analysis::text_width(c.name, 2));
  p.right = Plot::legend_gap + 34 + longest;
  return p;
}

analysis::Colour parse_colour(const std::string& hex) {
  const unsigned v = unsigned(std::stoul(hex.substr(1), nullptr, 16));
  return {static_cast<unsigned char>(v >> 16), static_cast<unsigned char>(v >> 8),
          static_cast<unsigned char>(v)};
}

}  // namespace

std::string to_svg(const std::vector<Row>& rows, const std::string& title) {
  const Plot p = layout(rows);
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << p.W() << "\" height=\"" << p.H
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << p.left << "\" y=\"24\" font-size=\"15\">" << title << "</text>\n";
  for (double d = p.x0; d <= p.x1; ++d) {
    const double x = p.px(std::pow(10, d));
    s << "<line x1=\"" << x << "\" y1=\"" << p.top << "\" x2=\"" << x << "\" y2=\""
      << p.H - p.bottom << "\" stroke=\"#ddd\"/>\n<text x=\"" << x << "\" y=\""
      << p.H - p.bottom + 16 << "\" text-anchor=\"middle\">" << format("%g", std::pow(10, d))
      << "</text>\n";
  }
  for (double d = p.y0; d <= p.y1; ++d) {
    const double y = p.py(std::pow(10, d));
    s << "<line x1=\"" << p.left << "\" y1=\"" << y << "\" x2=\"" << p.frame_right() << "\" y2=\""
      << y << "\" stroke=\"#ddd\"/>\n<text x=\"" << p.left - 6 << "\" y=\"" << y + 4
      << "\" text-anchor=\"end\">" << format("%g%%", 100 * std::pow(10, d)) << "</text>\n";
  }
  s << "<rect x=\"" << p.left << "\" y=\"" << p.top << "\" width=\"" << p.frame << "\" height=\""
    << p.H - p.top - p.bottom << "\" fill=\"none\" stroke=\"#333\"/>\n"
    << "<text x=\"" << (p.left + p.frame_right()) / 2 << "\" y=\"" << p.H - 12
    << "\" text-anchor=\"middle\">computation time (ms)</text>\n"
    << "<text transform=\"translate(18," << (p.top + p.H - p.bottom) / 2
    << ") rotate(-90)\" text-anchor=\"middle\">relative RMSE against the reference</text>\n";
  double legend_y = p.top + 10;
  for (const Plot::Series& c : p.series) {
    if (c.line) {
      s << "<polyline fill=\"none\" stroke=\"" << c.colour << "\" stroke-width=\"2\" points=\"";
      for (auto [x, y] : c.points) s << x << "," << y << " ";
      s << "\"/>\n";
      for (auto [x, y] : c.points)
        s << "<circle cx=\"" << x << "\" cy=\"" << y << "\" r=\"3\" fill=\"" << c.colour
          << "\"/>\n";
    } else {
      s << "<rect x=\"" << c.points[0].first - 4 << "\" y=\"" << c.points[0].second - 4
        << "\" width=\"8\" height=\"8\" fill=\"" << c.colour << "\"/>\n<text x=\""
        << c.points[0].first + 6 << "\" y=\"" << c.points[0].second - 4 << "\" font-size=\"11\">"
        << c.tag << "</text>\n";
    }
    s << "<rect x=\"" << p.frame_right() + p.legend_gap << "\" y=\"" << legend_y - 8
      << "\" width=\"14\" height=\"8\" fill=\"" << c.colour << "\"/><text x=\""
      << p.frame_right() + p.legend_gap + 20 << "\" y=\"" << legend_y << "\">" << c.name
      << "</text>\n";
    legend_y += p.legend_step;
  }
  s << "</svg>\n";
  return s.str();
}

ImageRgb8 to_png_plot(const std::vector<Row>& rows, const std::string& title) {
  const Plot p = layout(rows);
  ImageRgb8 img{int(p.W()), int(p.H),
                std::vector<unsigned char>(std::size_t(p.W() * p.H * 3), 255)};
  const analysis::Colour grid{221, 221, 221}, ink{40, 40, 40};
  auto line = [&](double ax, double ay, double bx, double by, analysis::Colour c, int thick) {
    const int n = int(std::max(std::abs(bx - ax), std::abs(by - ay))) + 1;
    for (int i = 0; i <= n; ++i) {
      const double f = double(i) / n;
      analysis::fill_rect(img, int(ax + f * (bx - ax)) - thick / 2,
                          int(ay + f * (by - ay)) - thick / 2, thick, thick, c);
    }
  };
  const int scale = 2, half = analysis::line_height(scale) / 2;
  analysis::draw_text(img, int(p.left), 10, title, ink, scale);
  for (double d = p.x0; d <= p.x1; ++d) {
    const double x = p.px(std::pow(10, d));
    line(x, p.top, x, p.H - p.bottom, grid, 1);
    const std::string label = format("%g", std::pow(10, d));
    analysis::draw_text(img, int(x) - analysis::text_width(label, scale) / 2,
                        int(p.H - p.bottom) + 6, label, ink, scale);
  }
  for (double d = p.y0; d <= p.y1; ++d) {
    const double y = p.py(std::pow(10, d));
    line(p.left, y, p.frame_right(), y, grid, 1);
    const std::string label = format("%g%%", 100 * std::pow(10, d));
    analysis::draw_text(img, int(p.left) - 6 - analysis::text_width(label, scale), int(y) - half,
                        label, ink, scale);
  }
  line(p.left, p.top, p.frame_right(), p.top, ink, 1);
  line(p.left, p.H - p.bottom, p.frame_right(), p.H - p.bottom, ink, 1);
  line(p.left, p.top, p.left, p.H - p.bottom, ink, 1);
  line(p.frame_right(), p.top, p.frame_right(), p.H - p.bottom, ink, 1);
  const std::string xlabel = "computation time (ms); y: relative RMSE";
  analysis::draw_text(img,
                      int((p.left + p.frame_right()) / 2) - analysis::text_width(xlabel, scale) / 2,
                      int(p.H) - 22, xlabel, ink, scale);
  int legend_y = int(p.top) + 4;
  for (const Plot::Series& c : p.series) {
    const analysis::Colour colour = parse_colour(c.colour);
    if (c.line) {
      for (std::size_t i = 0; i + 1 < c.points.size(); ++i)
        line(c.points[i].first, c.points[i].second, c.points[i + 1].first, c.points[i + 1].second,
             colour, 2);
      for (auto [x, y] : c.points) analysis::fill_rect(img, int(x) - 3, int(y) - 3, 7, 7, colour);
    } else {
      analysis::fill_rect(img, int(c.points[0].first) - 4, int(c.points[0].second) - 4, 9, 9,
                          colour);
      analysis::draw_text(img, int(c.points[0].first) + 6,
                          int(c.points[0].second) - 4 - analysis::line_height(2) / 2, c.tag, ink,
                          2);
    }
    analysis::fill_rect(img, int(p.frame_right() + p.legend_gap), legend_y + 2, 14, 8, colour);
    analysis::draw_text(img, int(p.frame_right() + p.legend_gap) + 20, legend_y, c.name, ink,
                        scale);
    legend_y += int(p.legend_step);
  }
  return img;
}

std::uint64_t scene_hash(const Scene& scene) {
  Fnv1a f;
  f.bytes(&scene.width, sizeof scene.width);
  f.bytes(&scene.height, sizeof scene.height);
  f.bytes(&scene.environment, sizeof scene.environment);
  f.bytes(scene.emission.data(), scene.emission.size() * sizeof(float));
  f.bytes(scene.opacity.data(), scene.opacity.size() * sizeof(float));
  f.bytes(scene.albedo.data(), scene.albedo.size() * sizeof(float));
  return f.h;
}

}  // namespace penumbra::study
