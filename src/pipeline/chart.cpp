// chart.cpp: see chart.h.
#include "pipeline/chart.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

#include "hbil/error.h"
#include "io/exr_output.h"

namespace hbil::pipeline {

namespace {

constexpr int kPanelW = 560, kPanelH = 400;
constexpr int kLeft = 64, kRight = 24, kTop = 48, kBottom = 56;
constexpr std::array<float, 3> kBlack{0.f, 0.f, 0.f}, kGrey{0.8f, 0.8f, 0.8f};

// What is drawn, in pixels of the whole chart (y down).
struct Line {
  double x0, y0, x1, y1;
  std::array<float, 3> colour;
  double width;
};
struct Marker {
  double x, y, r;
  std::array<float, 3> colour;
  bool square, filled;
};
struct Text {
  double x, y;
  std::string text;
  int size;
  int anchor;  // -1 start, 0 middle, 1 end
  std::array<float, 3> colour;
};
struct Drawing {
  int width = 0, height = 0;
  std::vector<Line> lines;
  std::vector<Marker> markers;
  std::vector<Text> texts;
};

// Ticks at 1, 2, 5 x 10^k covering [lo, hi], about `want` of them.
std::vector<double> linear_ticks(double lo, double hi, int want) {
  const double raw = (hi - lo) / std::max(want, 1);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  std::vector<double> t;
  for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) t.push_back(v);
  return t;
}

std::vector<double> log_ticks(double lo, double hi) {
  std::vector<double> t;
  for (int e = int(std::floor(std::log10(lo))); e <= int(std::ceil(std::log10(hi))); ++e)
    for (double m : {1.0, 2.0, 5.0}) {
      const double v = m * std::pow(10.0, e);
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) t.push_back(v);
    }
  if (t.size() < 2) t = {lo, hi};
  return t;
}

std::string tick_text(double v) {
  char b[32];
  if (std::fabs(v) >= 100 || v == std::round(v))
    std::snprintf(b, sizeof b, "%g", v);
  else
    std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

void draw_panel(const ChartPanel& p, int ox, Drawing& d) {
  double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo, ylo = xlo, yhi = -xlo;
  for (const auto& s : p.series)
    for (const auto& pt : s.points) {
      if (!std::isfinite(pt.x) || !std::isfinite(pt.y) || (p.log_x && pt.x <= 0)) continue;
      xlo = std::min(xlo, pt.x), xhi = std::max(xhi, pt.x);
      ylo = std::min(ylo, pt.y), yhi = std::max(yhi, pt.y);
    }
  if (!std::isfinite(xlo)) xlo = 0.1, xhi = 1, ylo = 0, yhi = 1;
  // Margins around the data: a factor 1.5 in log x, 8 % in y.
  if (p.log_x) {
    xlo /= 1.5, xhi *= 1.5;
  } else {
    const double m = std::max(xhi - xlo, 1e-6) * 0.08;
    xlo -= m, xhi += m;
  }
  const double my = std::max(yhi - ylo, 0.5) * 0.08;
  ylo -= my, yhi += my;
  const double px0 = ox + kLeft, px1 = ox + kPanelW - kRight, py0 = kTop, py1 = kPanelH - kBottom;
  auto X = [&](double x) {
    const double u = p.log_x ? (std::log(x) - std::log(xlo)) / (std::log(xhi) - std::log(xlo))
                             : (x - xlo) / (xhi - xlo);
    return px0 + u * (px1 - px0);
  };
  auto Y = [&](double y) { return py1 - (y - ylo) / (yhi - ylo) * (py1 - py0); };
  // Grid, ticks, frame.
  for (double t : p.log_x ? log_ticks(xlo, xhi) : linear_ticks(xlo, xhi, 6)) {
    d.lines.push_back({X(t), py0, X(t), py1, kGrey, 1});
    d.texts.push_back({X(t), py1 + 18, tick_text(t), 12, 0, kBlack});
  }
  for (double t : linear_ticks(ylo, yhi, 6)) {
    d.lines.push_back({px0, Y(t), px1, Y(t), kGrey, 1});
    d.texts.push_back({px0 - 6, Y(t) + 4, tick_text(t), 12, 1, kBlack});
  }
  d.lines.push_back({px0, py0, px1, py0, kBlack, 1});
  d.lines.push_back({px0, py1, px1, py1, kBlack, 1});
  d.lines.push_back({px0, py0, px0, py1, kBlack, 1});
  d.lines.push_back({px1, py0, px1, py1, kBlack, 1});
  d.texts.push_back({ox + kPanelW / 2.0, 22, p.title, 15, 0, kBlack});
  d.texts.push_back({(px0 + px1) / 2, kPanelH - 14.0, p.x_label, 13, 0, kBlack});
  d.texts.push_back({px0, py0 - 8, p.y_label, 12, -1, kBlack});
  // Series, legend at the top left inside the plot.
  double ly = py0 + 16;
  for (const auto& s : p.series) {
    std::vector<std::pair<double, double>> at;
    for (const auto& pt : s.points)
      if (std::isfinite(pt.x) && std::isfinite(pt.y) && (!p.log_x || pt.x > 0))
        at.emplace_back(X(pt.x), Y(pt.y));
    if (s.connect)
      for (size_t i = 1; i < at.size(); ++i)
        d.lines.push_back(
            {at[i - 1].first, at[i - 1].second, at[i].first, at[i].second, s.colour, 2});
    size_t k = 0;
    for (const auto& pt : s.points) {
      if (!std::isfinite(pt.x) || !std::isfinite(pt.y) || (p.log_x && pt.x <= 0)) continue;
      d.markers.push_back({at[k].first, at[k].second, 4.5, s.colour, s.square, pt.filled});
      if (!pt.label.empty())
        d.texts.push_back({at[k].first + 7, at[k].second - 6, pt.label, 11, -1, s.colour});
      ++k;
    }
    if (!s.name.empty()) {
      d.markers.push_back({px0 + 12, ly - 4, 4.5, s.colour, s.square, true});
      d.texts.push_back({px0 + 22, ly, s.name, 12, -1, s.colour});
      ly += 16;
    }
  }
}

Drawing draw(const std::vector<ChartPanel>& panels) {
  Drawing d;
  d.width = kPanelW * int(std::max<size_t>(panels.size(), 1));
  d.height = kPanelH;
  for (size_t i = 0; i < panels.size(); ++i) draw_panel(panels[i], int(i) * kPanelW, d);
  return d;
}

std::string rgb(const std::array<float, 3>& c) {
  char b[32];
  std::snprintf(b, sizeof b, "#%02x%02x%02x", int(std::lround(c[0] * 255)),
                int(std::lround(c[1] * 255)), int(std::lround(c[2] * 255)));
  return b;
}

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '&')
      o += "&amp;";
    else
      o += c;
  }
  return o;
}

// A font for the PNG's text: DejaVu Sans (Debian's fonts-dejavu-core), else OpenImageIO's
// own search.
std::string chart_font() {
  for (const char* f :
       {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", "/usr/share/fonts/TTF/DejaVuSans.ttf"})
    if (std::filesystem::exists(f)) return f;
  return "";
}

}  // namespace

std::string chart_svg(const std::vector<ChartPanel>& panels) {
  const Drawing d = draw(panels);
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << d.width << "\" height=\"" << d.height
    << "\" viewBox=\"0 0 " << d.width << " " << d.height
    << "\" font-family=\"DejaVu Sans, Verdana, sans-serif\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  for (const Line& l : d.lines)
    s << "<line x1=\"" << l.x0 << "\" y1=\"" << l.y0 << "\" x2=\"" << l.x1 << "\" y2=\"" << l.y1
      << "\" stroke=\"" << rgb(l.colour) << "\" stroke-width=\"" << l.width << "\"/>\n";
  for (const Marker& m : d.markers) {
    const std::string fill = m.filled ? rgb(m.colour) : "white";
    if (m.square)
      s << "<rect x=\"" << m.x - m.r << "\" y=\"" << m.y - m.r << "\" width=\"" << 2 * m.r
        << "\" height=\"" << 2 * m.r << "\"";
    else
      s << "<circle cx=\"" << m.x << "\" cy=\"" << m.y << "\" r=\"" << m.r << "\"";
    s << " fill=\"" << fill << "\" stroke=\"" << rgb(m.colour) << "\" stroke-width=\"1.5\"/>\n";
  }
  for (const Text& t : d.texts)
    s << "<text x=\"" << t.x << "\" y=\"" << t.y << "\" font-size=\"" << t.size
      << "\" text-anchor=\""
      << (t.anchor < 0   ? "start"
          : t.anchor > 0 ? "end"
                         : "middle")
      << "\" fill=\"" << rgb(t.colour) << "\">" << escape(t.text) << "</text>\n";
  s << "</svg>\n";
  return s.str();
}

void write_chart_png(const std::vector<ChartPanel>& panels, const std::string& path) {
  namespace IBA = OIIO::ImageBufAlgo;
  const Drawing d = draw(panels);
  OIIO::ImageBuf buf(OIIO::ImageSpec(d.width, d.height, 3, OIIO::TypeDesc::FLOAT));
  IBA::fill(buf, {1.f, 1.f, 1.f});
  for (const Line& l : d.lines) {
    // Width 2: drawn twice, a pixel apart across the line's direction.
    const bool steep = std::fabs(l.y1 - l.y0) > std::fabs(l.x1 - l.x0);
    for (int k = 0; k < int(std::lround(l.width)); ++k)
      IBA::render_line(buf, int(std::lround(l.x0)) + (steep ? k : 0),
                       int(std::lround(l.y0)) + (steep ? 0 : k),
                       int(std::lround(l.x1)) + (steep ? k : 0),
                       int(std::lround(l.y1)) + (steep ? 0 : k), l.colour);
  }
  for (const Marker& m : d.markers) {
    const int r = int(std::ceil(m.r)), cx = int(std::lround(m.x)), cy = int(std::lround(m.y));
    for (int y = cy - r; y <= cy + r; ++y)
      for (int x = cx - r; x <= cx + r; ++x) {
        if (x < 0 || y < 0 || x >= d.width || y >= d.height) continue;
        const double dx = x - m.x, dy = y - m.y, dist = std::sqrt(dx * dx + dy * dy);
        const bool inside = m.square ? std::max(std::fabs(dx), std::fabs(dy)) <= m.r : dist <= m.r;
        const bool edge =
            m.square ? std::max(std::fabs(dx), std::fabs(dy)) > m.r - 1.5 : dist > m.r - 1.5;
        if (inside && (m.filled || edge)) buf.setpixel(x, y, m.colour.data());
      }
  }
  const std::string font = chart_font();
  for (const Text& t : d.texts) {
    if (t.text.empty()) continue;
    const OIIO::ROI size = IBA::text_size(t.text, t.size, font);
    int x = int(std::lround(t.x));
    if (size.defined()) x -= t.anchor > 0 ? size.width() : t.anchor == 0 ? size.width() / 2 : 0;
    IBA::render_text(buf, x, int(std::lround(t.y)), t.text, t.size, font, t.colour);
  }
  io::Temporary tmp(path);
  if (!buf.write(tmp.path(), OIIO::TypeDesc::UINT8))
    throw Error(Exit::output, path + ": cannot write the chart: " + buf.geterror());
  io::commit(tmp.keep(), path);
}

}  // namespace hbil::pipeline
