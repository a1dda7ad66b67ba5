#include "client/parse.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

#include "glimpse/views/placement.h"
#include "proto/wire/methods.h"
#include "proto/wire/model_names.h"

namespace glimpse::client {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

}  // namespace

Expected<v1::ModelRef> ParseModelRef(std::string_view text, bool allow_latest) {
  v1::ModelRef ref;
  std::string_view name = text, version;
  if (auto colon = text.find(':'); colon != std::string_view::npos) {
    name = text.substr(0, colon);
    version = text.substr(colon + 1);
  }
  if (!wire::ValidateModelName(name).ok())
    return invalid_argument("bad model name '" + std::string(name) + "': 1-128 characters from [A-Za-z0-9._-]");
  ref.set_name(std::string(name));
  if (version.data() == nullptr) return ref;
  if (version == "latest") {
    if (allow_latest) return ref;
    return invalid_argument("'" + std::string(text) + "': 'latest' is for models set-default only; NAME alone is its " +
                            "default version (the newest unless one is pinned), NAME:N a version");
  }
  uint32_t v = 0;
  auto [end, ec] = std::from_chars(version.data(), version.data() + version.size(), v);
  if (ec != std::errc() || end != version.data() + version.size() || v == 0)
    return invalid_argument("bad model version '" + std::string(version) + "' in '" + std::string(text) +
                            "': a positive integer");
  ref.set_version(v);
  return ref;
}

Expected<FieldOfView> ParseFieldOfView(std::string_view text) {
  const std::string bad = "bad field of view '" + std::string(text) + "': HxV, full degrees in (0, 180), e.g. 57x43";
  const size_t x = text.find_first_of("xX");
  if (x == std::string_view::npos) return invalid_argument(bad);
  double v[2];
  const std::string_view items[2] = {Trim(text.substr(0, x)), Trim(text.substr(x + 1))};
  for (int k = 0; k < 2; ++k) {
    auto [end, ec] = std::from_chars(items[k].data(), items[k].data() + items[k].size(), v[k]);
    if (items[k].empty() || ec != std::errc() || end != items[k].data() + items[k].size() || !(v[k] > 0 && v[k] < 180))
      return invalid_argument(bad);
  }
  return FieldOfView{static_cast<float>(v[0]), static_cast<float>(v[1])};
}

Expected<UpChoice> ParseUpChoice(std::string_view text, bool allow_floor) {
  if (Trim(text) == "floor") {
    if (allow_floor) return UpChoice{std::nullopt, true};
    return invalid_argument("--up floor levels a single cloud file (classify, stream) by the floor it shows; give an "
                            "axis here: +z, -y, x, ... or \"x y z\"");
  }
  auto axis = parse_up(text);
  if (!axis) return axis.error();
  return UpChoice{*axis, false};
}

Expected<Vec3> ParseSensor(std::string_view text) {
  const std::string bad = "bad sensor '" + std::string(text) + "': three finite numbers X,Y,Z in the cloud's own frame and unit";
  Vec3 out;
  std::string_view rest = text;
  for (int axis = 0; axis < 3; ++axis) {
    const size_t comma = rest.find(',');
    if ((axis < 2) == (comma == std::string_view::npos)) return invalid_argument(bad);
    const std::string_view item = Trim(rest.substr(0, comma));
    double v = 0;
    auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || ec != std::errc() || end != item.data() + item.size() || !std::isfinite(v) ||
        std::abs(v) > 1e6)
      return invalid_argument(bad);
    out[axis] = static_cast<float>(v);
    if (axis < 2) rest = rest.substr(comma + 1);
  }
  return out;
}

std::string FormatModelRef(const v1::ModelRef& ref) {
  return ref.version() == 0 ? ref.name() : ref.name() + ":" + std::to_string(ref.version());
}

Expected<std::vector<v1::Method>> ParseMethodList(std::string_view text) {
  std::vector<v1::Method> methods;
  if (Trim(text).empty()) return methods;
  while (true) {
    const size_t comma = text.find(',');
    auto m = wire::ParseMethod(text.substr(0, comma));
    if (!m) return m.error();
    if (std::find(methods.begin(), methods.end(), *m) != methods.end())
      return invalid_argument("method '" + wire::MethodName(*m) + "' given twice");
    methods.push_back(*m);
    if (comma == std::string_view::npos) break;
    text.remove_prefix(comma + 1);
  }
  return methods;
}

Expected<v1::TrackTarget> ParseTrackTarget(std::string_view text) {
  const std::string bad = "bad target '" + std::string(text) +
                          "': 'nearest' (the object nearest the camera's axis), X,Y,Z (the object at that point) or "
                          "X0,Y0,Z0,X1,Y1,Z1 (the object in that box), finite metres in the stream's frame";
  v1::TrackTarget target;
  if (Trim(text) == "nearest") {
    target.set_nearest_axis(true);
    return target;
  }
  std::vector<double> v;
  for (std::string_view rest = text;;) {
    const size_t comma = rest.find(',');
    const std::string_view item = Trim(rest.substr(0, comma));
    double x = 0;
    auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), x);
    if (item.empty() || ec != std::errc() || end != item.data() + item.size() || !std::isfinite(x)) return invalid_argument(bad);
    v.push_back(x);
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  auto set = [&v](v1::Vec3* out, size_t at) { out->set_x(float(v[at])), out->set_y(float(v[at + 1])), out->set_z(float(v[at + 2])); };
  if (v.size() == 3) {
    set(target.mutable_point(), 0);
  } else if (v.size() == 6) {
    if (v[0] > v[3] || v[1] > v[4] || v[2] > v[5]) return invalid_argument(bad + " (the box's first corner is its minimum)");
    set(target.mutable_box()->mutable_min(), 0);
    set(target.mutable_box()->mutable_max(), 3);
  } else {
    return invalid_argument(bad);
  }
  return target;
}

}  // namespace glimpse::client
