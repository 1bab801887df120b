#include "line_map_eval/batch/figures.hpp"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace line_map_eval
{
using linemap::Segment2;
using linemap::Vec2;

namespace
{
constexpr double kMaxCanvas = 20000.0;  // Cairo image surfaces stop at 32767 pixels a side

struct Bounds
{
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  void add(const Vec2& p)
  {
    if (!p.allFinite()) return;
    min_x = std::min(min_x, p.x());
    min_y = std::min(min_y, p.y());
    max_x = std::max(max_x, p.x());
    max_y = std::max(max_y, p.y());
  }
  bool empty() const { return !(min_x <= max_x); }
};

/// The scan points' extent without its stray tails: a reading through a window or a phantom return tens of
/// metres out would otherwise shrink the building to a corner of the figure. Per axis the frame spans the
/// 0.2 % to 99.8 % quantiles (widened by 2 %), or every point when there are fewer than 1000; points outside
/// are not drawn. Map segments always lie inside (they are added in full).
void addRobustBounds(const std::vector<Vec2>& points, Bounds& b)
{
  std::vector<double> xs, ys;
  xs.reserve(points.size());
  ys.reserve(points.size());
  for (const Vec2& p : points)
    if (p.allFinite())
    {
      xs.push_back(p.x());
      ys.push_back(p.y());
    }
  if (xs.empty()) return;
  if (xs.size() < 1000)
  {
    for (std::size_t i = 0; i < xs.size(); ++i) b.add(Vec2(xs[i], ys[i]));
    return;
  }
  const auto quantile = [](std::vector<double>& v, double q)
  {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[static_cast<std::size_t>(k)];
  };
  const double x0 = quantile(xs, 0.002), x1 = quantile(xs, 0.998);
  const double y0 = quantile(ys, 0.002), y1 = quantile(ys, 0.998);
  const double mx = 0.02 * (x1 - x0), my = 0.02 * (y1 - y0);
  b.add(Vec2(x0 - mx, y0 - my));
  b.add(Vec2(x1 + mx, y1 + my));
}

/// Throws for a surface in error state (destroying it first, so nothing leaks).
void checkSurface(cairo_surface_t* s, const std::string& file)
{
  const cairo_status_t status = cairo_surface_status(s);
  if (status == CAIRO_STATUS_SUCCESS) return;
  cairo_surface_destroy(s);
  throw std::runtime_error("figure: cannot write '" + file + "': " + cairo_status_to_string(status));
}

void throwIfFailed(cairo_status_t status, const std::string& file)
{
  if (status != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("figure: cannot write '" + file + "': " + cairo_status_to_string(status));
}

constexpr std::uint32_t kScanGrey = 0xFFB4B4B4u;  // opaque light grey, native-endian ARGB
constexpr std::uint32_t kUncoveredOrange = 0xFFFF8000u;
constexpr std::uint32_t kUnmappedCyan = 0xFF00B4F0u;  // neither the map's dark blue nor the orange

/// An image surface to set pixels in (flushed), or null when cairo cannot make one.
cairo_surface_t* pixelSurface(cairo_format_t format, int width, int height)
{
  cairo_surface_t* img = cairo_image_surface_create(format, width, height);
  if (cairo_surface_status(img) != CAIRO_STATUS_SUCCESS)
  {
    cairo_surface_destroy(img);
    return nullptr;
  }
  cairo_surface_flush(img);
  return img;
}

/// Dots of `colour` (dot x dot canvas units) at the points as an image covering panel k's map
/// area at `scale` image pixels per canvas unit: a raster layer keeps SVG/PDF small with 10^5 points.
void drawScanPoints(cairo_t* cr, const std::vector<Vec2>& points, const FigureLayout& l, int panel,
                    double scale, std::uint32_t colour = kScanGrey, double dot = 1.0)
{
  if (points.empty()) return;
  const int w = std::max(1, static_cast<int>(std::ceil(l.map_width * scale)));
  const int h = std::max(1, static_cast<int>(std::ceil(l.map_height * scale)));
  cairo_surface_t* img = pixelSurface(CAIRO_FORMAT_ARGB32, w, h);
  if (!img) return;
  unsigned char* data = cairo_image_surface_get_data(img);
  const int stride = cairo_image_surface_get_stride(img);
  const double ppm = l.pixels_per_metre * scale;
  const int size = std::max(1, static_cast<int>(std::lround(dot * scale)));
  for (const Vec2& p : points)
  {
    if (!p.allFinite()) continue;
    const double fx = (p.x() - l.min_x) * ppm, fy = (l.max_y - p.y()) * ppm;
    if (fx < 0.0 || fy < 0.0 || fx >= w || fy >= h) continue;
    // A dot larger than a pixel is centred on the point's pixel.
    const int x0 = static_cast<int>(fx) - (size - 1) / 2, y0 = static_cast<int>(fy) - (size - 1) / 2;
    for (int y = std::max(0, y0); y < std::min(h, y0 + size); ++y)
      for (int x = std::max(0, x0); x < std::min(w, x0 + size); ++x)
        reinterpret_cast<std::uint32_t*>(data + y * stride)[x] = colour;
  }
  cairo_surface_mark_dirty(img);
  cairo_save(cr);
  cairo_translate(cr, panel * l.panel_width + l.margin, l.margin);
  cairo_scale(cr, 1.0 / scale, 1.0 / scale);
  cairo_set_source_surface(cr, img, 0.0, 0.0);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
  cairo_paint(cr);
  cairo_restore(cr);
  cairo_surface_destroy(img);
}

void drawLookup(cairo_t* cr, const LookupTable& t, const FigureLayout& l, int panel)
{
  if (t.empty()) return;
  cairo_surface_t* img = pixelSurface(CAIRO_FORMAT_RGB24, t.width(), t.height());
  if (!img) return;
  unsigned char* data = cairo_image_surface_get_data(img);
  const int stride = cairo_image_surface_get_stride(img);
  const std::vector<float>& v = t.values();
  for (int iy = 0; iy < t.height(); ++iy)
  {
    // Table row 0 is the lowest y: it becomes the bottom image row.
    auto* row = reinterpret_cast<std::uint32_t*>(data + (t.height() - 1 - iy) * stride);
    for (int ix = 0; ix < t.width(); ++ix)
    {
      const float val = std::clamp(v[static_cast<std::size_t>(iy) * t.width() + ix], 0.0f, 1.0f);
      const auto g = static_cast<std::uint32_t>(std::lround(255.0 * (1.0 - 0.6 * val)));
      row[ix] = 0xFF000000u | (g << 16) | (g << 8) | g;
    }
  }
  cairo_surface_mark_dirty(img);
  const double res = t.resolution();
  const Vec2 top_left = l.toCanvas(Vec2(t.x0() * res, (t.y0() + t.height()) * res), panel);
  cairo_save(cr);
  cairo_translate(cr, top_left.x(), top_left.y());
  cairo_scale(cr, res * l.pixels_per_metre, res * l.pixels_per_metre);
  cairo_set_source_surface(cr, img, 0.0, 0.0);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
  cairo_paint(cr);
  cairo_restore(cr);
  cairo_surface_destroy(img);
}

std::string formatMetres(double m)
{
  char buf[32];
  if (m >= 1.0)
    std::snprintf(buf, sizeof buf, "%.0f m", m);
  else
    std::snprintf(buf, sizeof buf, "%g m", m);
  return buf;
}

void setColour(cairo_t* cr, std::uint32_t argb)
{
  cairo_set_source_rgb(cr, ((argb >> 16) & 0xFF) / 255.0, ((argb >> 8) & 0xFF) / 255.0,
                       (argb & 0xFF) / 255.0);
}

const double kMapBlue[3] = {0.05, 0.10, 0.45};
const double kRedundantMagenta[4] = {0.85, 0.0, 0.85, 0.45};
const double kTrajectoryBlack[4] = {0.0, 0.0, 0.0, 1.0};
const double kAcceptedGreen[4] = {0.0, 0.65, 0.0, 0.8};
const double kRejectedOrange[4] = {1.0, 0.55, 0.0, 0.6};
const double kBadRelationRed[4] = {0.9, 0.0, 0.0, 0.9};

/// Straight lines in panel k, one stroke.
void drawLines(cairo_t* cr, const std::vector<Segment2>& lines, const FigureLayout& l, int panel,
               const double* rgba, double width)
{
  if (lines.empty()) return;
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_width(cr, width);
  cairo_set_source_rgba(cr, rgba[0], rgba[1], rgba[2], rgba[3]);
  for (const Segment2& s : lines)
  {
    if (!s.start.allFinite() || !s.end.allFinite()) continue;
    const Vec2 a = l.toCanvas(s.start, panel), b = l.toCanvas(s.end, panel);
    cairo_move_to(cr, a.x(), a.y());
    cairo_line_to(cr, b.x(), b.y());
  }
  cairo_stroke(cr);
}

/// A SLAM run's layers: rejected closures, accepted ones, the trajectory, then the bad relations on top.
void drawSlamLayers(cairo_t* cr, const MapFigure& f, const FigureLayout& l, int panel,
                    const FigureStyle& style)
{
  drawLines(cr, f.rejected_closures, l, panel, kRejectedOrange, 0.6 * style.line_width);
  drawLines(cr, f.accepted_closures, l, panel, kAcceptedGreen, 0.6 * style.line_width);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_width(cr, 0.6 * style.line_width);
  cairo_set_source_rgba(cr, kTrajectoryBlack[0], kTrajectoryBlack[1], kTrajectoryBlack[2],
                        kTrajectoryBlack[3]);
  bool pen_down = false;
  for (const Vec2& p : f.trajectory)
  {
    if (!p.allFinite())
    {
      pen_down = false;
      continue;
    }
    const Vec2 c = l.toCanvas(p, panel);
    if (pen_down)
      cairo_line_to(cr, c.x(), c.y());
    else
      cairo_move_to(cr, c.x(), c.y());
    pen_down = true;
  }
  cairo_stroke(cr);
  if (f.show_relations) drawLines(cr, f.bad_relations, l, panel, kBadRelationRed, style.line_width);
}

/// One line of legend entries (a glyph and a label each), left to right from x, centred on y.
class LegendLine
{
 public:
  LegendLine(cairo_t* cr, double x, double y, const FigureStyle& style, std::vector<std::string>* labels)
      : cr_(cr), x_(x), y_(y), style_(style), labels_(labels)
  {
  }

  void label(const std::string& text)
  {
    if (labels_) labels_->push_back(text);
    cairo_set_source_rgb(cr_, 0.0, 0.0, 0.0);
    cairo_move_to(cr_, x_ + kGlyph + 4.0, y_ + 0.3 * style_.font_size);
    cairo_show_text(cr_, text.c_str());
    cairo_text_extents_t ext;
    cairo_text_extents(cr_, text.c_str(), &ext);
    x_ += kGlyph + 4.0 + ext.x_advance + 14.0;
  }
  void line(const double* rgba, double width)
  {
    cairo_set_line_cap(cr_, CAIRO_LINE_CAP_ROUND);
    cairo_set_line_width(cr_, width);
    cairo_set_source_rgba(cr_, rgba[0], rgba[1], rgba[2], rgba[3]);
    cairo_move_to(cr_, x_ + 2.0, y_);
    cairo_line_to(cr_, x_ + kGlyph - 2.0, y_);
    cairo_stroke(cr_);
  }
  void disc(double r, double g, double b)
  {
    cairo_set_source_rgb(cr_, r, g, b);
    cairo_new_sub_path(cr_);
    cairo_arc(cr_, x_ + 0.5 * kGlyph, y_, style_.endpoint_radius, 0.0, 2.0 * linemap::kPi);
    cairo_fill(cr_);
  }
  void square(std::uint32_t argb, double side)
  {
    setColour(cr_, argb);
    cairo_rectangle(cr_, x_ + 0.5 * (kGlyph - side), y_ - 0.5 * side, side, side);
    cairo_fill(cr_);
  }

 private:
  static constexpr double kGlyph = 14.0;
  cairo_t* cr_;
  double x_, y_;
  const FigureStyle& style_;
  std::vector<std::string>* labels_;  ///< when not null, every label drawn is appended
};

void drawLegend(cairo_t* cr, const MapFigure& f, double x, double y, const FigureStyle& style,
                std::vector<std::string>* labels = nullptr)
{
  cairo_save(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 0.85 * style.font_size);
  LegendLine legend(cr, x, y, style, labels);
  if (!f.show_slam || !f.segments.empty())
  {
    const double blue[4] = {kMapBlue[0], kMapBlue[1], kMapBlue[2], 1.0};
    legend.line(blue, style.line_width);
    legend.label("map segment");
    legend.disc(0.90, 0.0, 0.0);
    legend.label("start");
    legend.disc(0.0, 0.70, 0.0);
    legend.label("end");
  }
  if (!f.scan_points.empty())
  {
    legend.square(kScanGrey, 4.0);
    legend.label("scan point");
  }
  if (f.lookup)
  {
    legend.square(0xFF999999u, 10.0);  // the table's 1 (grey 40 %); 0 is white
    legend.label("lookup table (white 0 to grey 1)");
  }
  if (f.show_coverage)
  {
    legend.square(kUncoveredOrange, 4.0);
    legend.label("uncovered scan point (" + std::to_string(f.uncovered_points.size()) + ")");
    legend.square(kUnmappedCyan, 4.0);
    legend.label("unmapped straight structure (" + std::to_string(f.uncovered_structure_points.size()) + ")");
    legend.line(kRedundantMagenta, 4.0 * style.line_width);
    legend.label("redundant pair (" + std::to_string(f.redundant_pairs.size()) + ")");
  }
  if (f.show_slam)
  {
    legend.line(kTrajectoryBlack, style.line_width);
    legend.label("trajectory");
    legend.line(kAcceptedGreen, 2.0 * style.line_width);
    legend.label("accepted closure (" + std::to_string(f.accepted_closures.size()) + ")");
    legend.line(kRejectedOrange, 2.0 * style.line_width);
    legend.label("rejected closure (" + std::to_string(f.rejected_closures.size()) + ")");
  }
  if (f.show_relations)
  {
    char limit[32];
    std::snprintf(limit, sizeof limit, "%g", f.bad_relation);
    legend.line(kBadRelationRed, 2.0 * style.line_width);
    legend.label(std::string("relation error > ") + limit + " m (" + std::to_string(f.bad_relations.size()) +
                 ")");
  }
  cairo_restore(cr);
}

void drawPanel(cairo_t* cr, const MapFigure& f, const FigureLayout& l, int panel, const FigureStyle& style,
               double raster_scale)
{
  const double ax = panel * l.panel_width + l.margin, ay = l.margin;
  cairo_save(cr);
  cairo_rectangle(cr, ax, ay, l.map_width, l.map_height);
  cairo_clip(cr);
  if (f.lookup) drawLookup(cr, *f.lookup, l, panel);
  drawScanPoints(cr, f.scan_points, l, panel, raster_scale);
  // Uncovered points as large as the grey ones, so the picture shows their true share.
  if (f.show_coverage)
  {
    drawScanPoints(cr, f.uncovered_points, l, panel, raster_scale, kUncoveredOrange);
    drawScanPoints(cr, f.uncovered_structure_points, l, panel, raster_scale, kUnmappedCyan);
  }

  // Redundant pairs under the map: a wide translucent band over both segments of each pair.
  if (f.show_coverage && !f.redundant_pairs.empty())
  {
    std::vector<Segment2> both;
    for (const auto& pair : f.redundant_pairs)
    {
      both.push_back(pair.first);
      both.push_back(pair.second);
    }
    drawLines(cr, both, l, panel, kRedundantMagenta, 4.0 * style.line_width);
  }
  if (f.show_slam) drawSlamLayers(cr, f, l, panel, style);

  const double blue[4] = {kMapBlue[0], kMapBlue[1], kMapBlue[2], 1.0};
  drawLines(cr, f.segments, l, panel, blue, style.line_width);
  // Ends first, starts on top: on chained segments the start of the next one stays visible.
  const auto discs = [&](bool starts)
  {
    for (const Segment2& s : f.segments)
    {
      const Vec2& w = starts ? s.start : s.end;
      if (!w.allFinite()) continue;
      const Vec2 c = l.toCanvas(w, panel);
      cairo_new_sub_path(cr);
      cairo_arc(cr, c.x(), c.y(), style.endpoint_radius, 0.0, 2.0 * linemap::kPi);
    }
    cairo_fill(cr);
  };
  cairo_set_source_rgb(cr, 0.0, 0.70, 0.0);
  discs(false);
  cairo_set_source_rgb(cr, 0.90, 0.0, 0.0);
  discs(true);
  cairo_restore(cr);

  // Caption band: caption on the left, scale bar on the right.
  const double base = ay + l.map_height + l.margin;
  const double mid = base + 0.5 * l.caption_height;
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, style.font_size);
  cairo_set_source_rgb(cr, 0.0, 0.0, 0.0);
  cairo_move_to(cr, ax, mid + 0.35 * style.font_size);
  cairo_show_text(cr, f.caption.c_str());

  const double bar_m = scaleBarLength(l.max_x - l.min_x);
  const double bar = bar_m * l.pixels_per_metre;
  const double x1 = ax + l.map_width, x0 = x1 - bar;
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  cairo_set_line_width(cr, 2.0);
  cairo_move_to(cr, x0, mid - 4.0);
  cairo_line_to(cr, x0, mid + 4.0);
  cairo_move_to(cr, x0, mid);
  cairo_line_to(cr, x1, mid);
  cairo_move_to(cr, x1, mid - 4.0);
  cairo_line_to(cr, x1, mid + 4.0);
  cairo_stroke(cr);
  const std::string label = formatMetres(bar_m);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, label.c_str(), &ext);
  cairo_move_to(cr, x0 - ext.x_advance - 6.0, mid + 0.35 * style.font_size);
  cairo_show_text(cr, label.c_str());

  if (l.legend_height > 0.0)
  {
    // Clipped to the panel: a narrow panel shows the first entries.
    cairo_save(cr);
    cairo_rectangle(cr, ax, base + l.caption_height, l.map_width, l.legend_height);
    cairo_clip(cr);
    drawLegend(cr, f, ax, base + l.caption_height + 0.5 * l.legend_height, style);
    cairo_restore(cr);
  }
}

void render(cairo_t* cr, const std::vector<const MapFigure*>& panels, const FigureLayout& l,
            const FigureStyle& style, double raster_scale)
{
  cairo_set_source_rgb(cr, 1.0, 1.0, 1.0);
  cairo_paint(cr);
  for (std::size_t k = 0; k < panels.size(); ++k)
    drawPanel(cr, *panels[k], l, static_cast<int>(k), style, raster_scale);
}

bool endsWith(const std::string& s, const std::string& suffix)
{
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// Renders the panels into a vector file made by `create` (cairo's SVG or PDF surface) and returns its name.
std::string drawVector(cairo_surface_t* (*create)(const char*, double, double), const std::string& file,
                       const std::vector<const MapFigure*>& panels, const FigureLayout& l,
                       const FigureStyle& style)
{
  cairo_surface_t* s = create(file.c_str(), l.width, l.height);
  checkSurface(s, file);
  cairo_t* cr = cairo_create(s);
  render(cr, panels, l, style, 2.0);
  cairo_destroy(cr);
  cairo_surface_finish(s);
  const cairo_status_t st = cairo_surface_status(s);
  cairo_surface_destroy(s);
  throwIfFailed(st, file);
  return file;
}

std::vector<std::string> drawPanels(const std::vector<const MapFigure*>& panels, const std::string& path,
                                    unsigned formats, const FigureStyle& style)
{
  std::string base = path;
  for (const auto& [ext, fmt] : {std::pair<const char*, unsigned>{".svg", kFigureSvg},
                                 std::pair<const char*, unsigned>{".pdf", kFigurePdf},
                                 std::pair<const char*, unsigned>{".png", kFigurePng}})
    if (endsWith(path, ext))
    {
      base = path.substr(0, path.size() - 4);
      formats = fmt;
    }
  if ((formats & kFigureAllFormats) == 0)
    throw std::invalid_argument("figure '" + path + "': no output format selected");
  const FigureLayout l = layoutFigure(panels, style);
  std::vector<std::string> written;

  if (formats & kFigureSvg)
    written.push_back(drawVector(cairo_svg_surface_create, base + ".svg", panels, l, style));
  if (formats & kFigurePdf)
    written.push_back(drawVector(cairo_pdf_surface_create, base + ".pdf", panels, l, style));
  if (formats & kFigurePng)
  {
    const std::string file = base + ".png";
    cairo_surface_t* s = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, l.pixelWidth(), l.pixelHeight());
    checkSurface(s, file);
    cairo_t* cr = cairo_create(s);
    render(cr, panels, l, style, 1.0);
    cairo_destroy(cr);
    const cairo_status_t st = cairo_surface_write_to_png(s, file.c_str());
    cairo_surface_destroy(s);
    throwIfFailed(st, file);
    written.push_back(file);
  }
  return written;
}
}  // namespace

int FigureLayout::pixelWidth() const
{
  return static_cast<int>(std::ceil(width - 1e-9));
}
int FigureLayout::pixelHeight() const
{
  return static_cast<int>(std::ceil(height - 1e-9));
}

std::vector<std::string> legendLabels(const MapFigure& figure, const FigureStyle& style)
{
  // The legend's own drawing code on a scratch surface: the labels are those a figure shows.
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, 1, 1);
  cairo_t* cr = cairo_create(surface);
  std::vector<std::string> labels;
  drawLegend(cr, figure, 0.0, 0.0, style, &labels);
  cairo_destroy(cr);
  cairo_surface_destroy(surface);
  return labels;
}

double scaleBarLength(double width)
{
  if (!(width > 0.0) || !std::isfinite(width)) return 1.0;
  const double limit = 0.25 * width;
  double p = std::pow(10.0, std::floor(std::log10(limit)));
  double best = p;
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p <= limit * (1.0 + 1e-12)) best = m * p;
  return best;
}

FigureLayout layoutFigure(const std::vector<const MapFigure*>& panels, const FigureStyle& style)
{
  if (panels.empty()) throw std::invalid_argument("figure: no panel to draw");
  if (!(style.margin >= 0.0) || !(style.caption_height >= 0.0) || !(style.legend_height >= 0.0) ||
      !(style.padding >= 0.0) || !(style.pixels_per_metre >= 0.0) || !(style.max_size > 0.0))
    throw std::invalid_argument(
        "figure: margin, caption_height, legend_height, padding, pixels_per_metre must be >= 0 and "
        "max_size > 0");
  Bounds b;
  for (const MapFigure* f : panels)
  {
    for (const Segment2& s : f->segments)
    {
      b.add(s.start);
      b.add(s.end);
    }
    addRobustBounds(f->scan_points, b);
    for (const Vec2& p : f->trajectory) b.add(p);
    if (f->lookup && !f->lookup->empty())
    {
      const LookupTable& t = *f->lookup;
      b.add(t.origin());
      b.add(t.origin() + t.resolution() * Vec2(t.width(), t.height()));
    }
  }
  if (b.empty()) b.add(Vec2(-1.0, -1.0)), b.add(Vec2(1.0, 1.0));
  FigureLayout l;
  l.panels = static_cast<int>(panels.size());
  l.min_x = b.min_x - style.padding;
  l.max_x = b.max_x + style.padding;
  l.min_y = b.min_y - style.padding;
  l.max_y = b.max_y + style.padding;
  double w = l.max_x - l.min_x, h = l.max_y - l.min_y;
  if (!(w > 0.0)) l.min_x -= 0.5, l.max_x += 0.5, w = 1.0;
  if (!(h > 0.0)) l.min_y -= 0.5, l.max_y += 0.5, h = 1.0;
  l.pixels_per_metre =
      style.pixels_per_metre > 0.0 ? style.pixels_per_metre : style.max_size / std::max(w, h);
  l.margin = style.margin;
  l.caption_height = style.caption_height;
  l.legend_height = style.legend_height;
  l.map_width = w * l.pixels_per_metre;
  l.map_height = h * l.pixels_per_metre;
  l.panel_width = l.map_width + 2.0 * l.margin;
  l.width = l.panels * l.panel_width;
  l.height = l.map_height + 2.0 * l.margin + l.caption_height + l.legend_height;
  if (l.width > kMaxCanvas || l.height > kMaxCanvas)
    throw std::invalid_argument("figure: canvas of " + std::to_string(l.width) + " x " +
                                std::to_string(l.height) + " exceeds 20000; lower pixels_per_metre");
  return l;
}

std::vector<std::string> drawMap(const MapFigure& figure, const std::string& path, unsigned formats,
                                 const FigureStyle& style)
{
  return drawPanels({&figure}, path, formats, style);
}

std::vector<std::string> drawLookupTable(const LookupTable& table, const std::vector<Segment2>& map,
                                         const std::string& caption, const std::string& path,
                                         unsigned formats, const FigureStyle& style)
{
  MapFigure f;
  f.segments = map;
  f.lookup = &table;
  f.caption = caption;
  return drawPanels({&f}, path, formats, style);
}

std::vector<std::string> drawComparison(const MapFigure& left, const MapFigure& right,
                                        const std::string& path, unsigned formats, const FigureStyle& style)
{
  return drawPanels({&left, &right}, path, formats, style);
}

}  // namespace line_map_eval
