#include "client/render_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "client/render.h"
#include "proto/wire/errors.h"
#include "proto/wire/methods.h"

namespace glimpse::client {
namespace {

std::string Vec(const v1::Vec3& v, int decimals, std::string_view sep) {
  return Fixed(v.x(), decimals) + std::string(sep) + Fixed(v.y(), decimals) + std::string(sep) + Fixed(v.z(), decimals);
}

std::string JsonVec(const v1::Vec3& v) {
  return "[" + JsonNumber(v.x()) + "," + JsonNumber(v.y()) + "," + JsonNumber(v.z()) + "]";
}

std::string StatusText(const v1::ClassifyResult& r) {
  return std::string(wire::StatusCodeName(static_cast<grpc::StatusCode>(r.code()))) + ": " + r.message();
}

// A winner's label on the SVG: "chair", "unknown", or the status code.
std::string ShortWinner(const v1::ClassifyResult& r) {
  if (r.code() != 0) return wire::StatusCodeName(static_cast<grpc::StatusCode>(r.code()));
  return r.response().unknown() ? "unknown" : r.response().winner();
}

std::string XmlEscaped(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

const char* Colour(size_t i) {
  static const char* kColours[] = {"#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd",
                                   "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"};
  return kColours[i % (sizeof(kColours) / sizeof(kColours[0]))];
}

}  // namespace

std::string SceneTable(const v1::ClassifySceneResponse& r) {
  const bool cut = std::any_of(r.objects().begin(), r.objects().end(),
                               [](const v1::SceneObject& o) { return o.result().response().frame_cut_size() > 0; });
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> header = {"#", "WINNER", "P", "NOVELTY", "POINTS", "RANGE_M", "SIZE_M", "CENTRE"};
  if (cut) header.push_back("CUT BY FRAME");
  rows.push_back(header);
  for (int i = 0; i < r.objects_size(); ++i) {
    const v1::SceneObject& o = r.objects(i);
    const v1::ClassifyResponse& c = o.result().response();
    const bool ok = o.result().code() == 0;
    v1::Vec3 size;
    size.set_x(o.box_max().x() - o.box_min().x()), size.set_y(o.box_max().y() - o.box_min().y());
    size.set_z(o.box_max().z() - o.box_min().z());
    std::vector<std::string> row = {std::to_string(i + 1), ok ? WinnerCell(c) : StatusText(o.result()),
                                    ok && !c.unknown() ? Score(WinnerShown(c)) : "-",
                                    ok && c.has_novelty() ? Fixed(c.novelty(), 2) : "-",
                                    std::to_string(o.points()), Fixed(o.range_m(), 2), Vec(size, 2, "x"),
                                    Vec(o.centroid(), 2, ",")};
    if (cut) {
      const std::vector<std::string> edges(c.frame_cut().begin(), c.frame_cut().end());
      row.push_back(edges.empty() ? "-" : Joined(edges, ","));
    }
    rows.push_back(std::move(row));
  }
  return Table(rows);
}

std::string SceneJson(std::string_view file, const v1::ClassifySceneResponse& r) {
  std::string planes, objects;
  for (const v1::ScenePlane& p : r.planes())
    planes += std::string(planes.empty() ? "" : ",") + "{\"normal\":" + JsonVec(p.normal()) +
              ",\"offset\":" + JsonNumber(p.offset()) + ",\"points\":" + std::to_string(p.points()) + "}";
  for (int i = 0; i < r.objects_size(); ++i) {
    const v1::SceneObject& o = r.objects(i);
    std::string answer = o.result().code() == 0
                             ? ClassifyJsonFields(o.result().response())
                             : "\"error\":{\"code\":" +
                                   JsonString(wire::StatusCodeName(static_cast<grpc::StatusCode>(o.result().code()))) +
                                   ",\"message\":" + JsonString(o.result().message()) + "}";
    objects += std::string(objects.empty() ? "" : ",") + "{\"object\":" + std::to_string(i + 1) +
               ",\"box_min\":" + JsonVec(o.box_min()) + ",\"box_max\":" + JsonVec(o.box_max()) +
               ",\"centroid\":" + JsonVec(o.centroid()) + ",\"range_m\":" + JsonNumber(o.range_m()) +
               ",\"points\":" + std::to_string(o.points()) + "," + answer + "}";
  }
  return "{\"file\":" + JsonString(file) + ",\"model\":" + JsonString(r.model().name()) +
         ",\"version\":" + std::to_string(r.model().version()) + ",\"method\":" + JsonString(wire::MethodName(r.method())) +
         ",\"frame_points\":" + std::to_string(r.frame_points()) + ",\"segment_ms\":" + JsonNumber(r.segment_ms()) +
         ",\"total_ms\":" + JsonNumber(r.total_ms()) + ",\"warning\":" + JsonString(r.warning()) +
         ",\"planes\":[" + planes + "],\"objects\":[" + objects + "]}";
}

namespace {

// Top view: metres (x, y) to SVG pixels (x right, y up), the frame's points and the sensor in view.
struct TopView {
  float min_x = 0, max_y = 0, scale = 1;
  static constexpr float kMargin = 30, kSize = 800;
  std::string X(float x) const { return Fixed(kMargin + (x - min_x) * scale, 1); }
  std::string Y(float y) const { return Fixed(kMargin + (max_y - y) * scale, 1); }
};

TopView FitView(const Points& frame, const std::optional<Vec3>& sensor) {
  float lo_x = INFINITY, hi_x = -INFINITY, lo_y = INFINITY, hi_y = -INFINITY;
  auto grow = [&](const Vec3& p) {
    lo_x = std::min(lo_x, p.x()), hi_x = std::max(hi_x, p.x()), lo_y = std::min(lo_y, p.y()), hi_y = std::max(hi_y, p.y());
  };
  for (const Vec3& p : frame) grow(p);
  if (sensor) grow(*sensor);
  if (!(lo_x <= hi_x)) lo_x = hi_x = lo_y = hi_y = 0;
  TopView v;
  v.min_x = lo_x, v.max_y = hi_y;
  v.scale = (TopView::kSize - 2 * TopView::kMargin) / std::max({hi_x - lo_x, hi_y - lo_y, 0.1f});
  return v;
}

}  // namespace

std::string SceneSvg(std::string_view title, const v1::ClassifySceneResponse& r, const Points& frame,
                     const std::optional<Vec3>& sensor, size_t max_points) {
  const TopView v = FitView(frame, sensor);
  std::vector<int> owner(frame.size(), -1);
  for (int i = 0; i < r.objects_size(); ++i)
    for (uint32_t k : r.objects(i).indices())
      if (k < owner.size()) owner[k] = i;
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"800\" height=\"830\" font-family=\"sans-serif\" "
                    "font-size=\"13\">\n<rect width=\"800\" height=\"830\" fill=\"white\"/>\n";
  const size_t stride = std::max<size_t>(1, (frame.size() + std::max<size_t>(max_points, 1) - 1) / std::max<size_t>(max_points, 1));
  for (size_t k = 0; k < frame.size(); k += stride) {
    const char* fill = owner[k] < 0 ? "#c8c8c8" : Colour(static_cast<size_t>(owner[k]));
    svg += "<circle cx=\"" + v.X(frame[k].x()) + "\" cy=\"" + v.Y(frame[k].y()) + "\" r=\"1\" fill=\"" + fill + "\"/>\n";
  }
  for (int i = 0; i < r.objects_size(); ++i) {
    const v1::SceneObject& o = r.objects(i);
    const char* colour = Colour(static_cast<size_t>(i));
    const float w = (o.box_max().x() - o.box_min().x()) * v.scale, h = (o.box_max().y() - o.box_min().y()) * v.scale;
    svg += "<rect x=\"" + v.X(o.box_min().x()) + "\" y=\"" + v.Y(o.box_max().y()) + "\" width=\"" + Fixed(w, 1) +
           "\" height=\"" + Fixed(h, 1) + "\" fill=\"none\" stroke=\"" + colour + "\" stroke-width=\"2\"/>\n";
    svg += "<text x=\"" + v.X(o.box_min().x()) + "\" y=\"" + Fixed(std::stof(v.Y(o.box_max().y())) - 4, 1) +
           "\" fill=\"" + colour + "\">" + std::to_string(i + 1) + " " + XmlEscaped(ShortWinner(o.result())) + "</text>\n";
  }
  if (sensor)
    svg += "<circle cx=\"" + v.X(sensor->x()) + "\" cy=\"" + v.Y(sensor->y()) + "\" r=\"5\" fill=\"black\"/>\n<text x=\"" +
           v.X(sensor->x()) + "\" y=\"" + Fixed(std::stof(v.Y(sensor->y())) + 18, 1) + "\">sensor</text>\n";
  svg += "<text x=\"10\" y=\"820\">" + XmlEscaped(title) + " (top view, x right, y up; " +
         Fixed(1.0 / v.scale * 100, 2) + " m per 100 px)</text>\n</svg>\n";
  return svg;
}

}  // namespace glimpse::client
