// chart.h: scatter charts of speed against accuracy, drawn once into lines, markers and text,
// then written as SVG and as PNG (OpenImageIO's drawing, DejaVu Sans for the text), so that a
// user opens the chart with no other tool.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace hbil::pipeline {

struct ChartSeries {
  std::string name;  // legend
  std::array<float, 3> colour{0.f, 0.f, 0.f};
  bool square = false;   // square markers (else circles)
  bool connect = false;  // a line through the points in order
  struct Point {
    double x = 0, y = 0;
    std::string label;
    bool filled = true;
  };
  std::vector<Point> points;
};

struct ChartPanel {
  std::string title, x_label, y_label;
  bool log_x = true;
  std::vector<ChartSeries> series;
};

// Panels side by side.
std::string chart_svg(const std::vector<ChartPanel>& panels);
// Throws Error(Exit::output) naming the file.
void write_chart_png(const std::vector<ChartPanel>& panels, const std::string& path);

}  // namespace hbil::pipeline
