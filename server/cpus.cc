#include "cpus.h"

#include <sched.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

namespace glimpse::server {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::optional<long long> ParseInt(std::string_view s) {
  s = Trim(s);
  long long v = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<std::string> ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::optional<double> Min(std::optional<double> a, std::optional<double> b) {
  if (!a) return b;
  if (!b) return a;
  return std::min(*a, *b);
}

// The quota of `dir` and each ancestor up to `root` (a child may not exceed its parents).
template <class Read>
std::optional<double> TightestUpTo(const std::filesystem::path& root, std::filesystem::path dir, Read read) {
  std::optional<double> best;
  for (int depth = 0; depth < 64; ++depth) {
    best = Min(best, read(dir));
    if (dir == root || !dir.has_parent_path() || dir.parent_path() == dir) break;
    const std::string d = dir.string(), r = root.string();
    if (d.size() <= r.size()) break;
    dir = dir.parent_path();
  }
  return best;
}

}  // namespace

std::optional<double> ParseCgroupV2CpuMax(std::string_view text) {
  text = Trim(text);
  const size_t space = text.find(' ');
  if (space == std::string_view::npos) return std::nullopt;
  const std::string_view quota = text.substr(0, space);
  if (quota == "max") return std::nullopt;
  auto q = ParseInt(quota), p = ParseInt(text.substr(space + 1));
  if (!q || !p || *q <= 0 || *p <= 0) return std::nullopt;
  return static_cast<double>(*q) / static_cast<double>(*p);
}

std::optional<double> ParseCgroupV1Quota(std::string_view quota_us, std::string_view period_us) {
  auto q = ParseInt(quota_us), p = ParseInt(period_us);
  if (!q || !p || *q <= 0 || *p <= 0) return std::nullopt;
  return static_cast<double>(*q) / static_cast<double>(*p);
}

std::optional<std::string> CgroupPath(std::string_view text, bool v2) {
  while (!text.empty()) {
    const size_t eol = text.find('\n');
    std::string_view line = text.substr(0, eol);
    text = eol == std::string_view::npos ? std::string_view() : text.substr(eol + 1);
    // hierarchy-ID:controller-list:path
    const size_t a = line.find(':'), b = a == std::string_view::npos ? a : line.find(':', a + 1);
    if (b == std::string_view::npos) continue;
    const std::string_view id = line.substr(0, a), controllers = line.substr(a + 1, b - a - 1);
    const std::string path(Trim(line.substr(b + 1)));
    if (v2 && id == "0" && controllers.empty()) return path;
    if (!v2) {
      std::string_view list = controllers;
      while (!list.empty()) {
        const size_t comma = list.find(',');
        if (list.substr(0, comma) == "cpu") return path;
        list = comma == std::string_view::npos ? std::string_view() : list.substr(comma + 1);
      }
    }
  }
  return std::nullopt;
}

std::optional<double> CgroupCpuQuota(const std::string& root_text, const std::string& proc_self_cgroup) {
  namespace fs = std::filesystem;
  const auto self = ReadFile(proc_self_cgroup);
  if (!self) return std::nullopt;
  const fs::path root(root_text);
  std::error_code ec;
  // v2: the unified hierarchy at the root (or, on hybrid systems, under root/unified).
  if (auto path = CgroupPath(*self, true)) {
    for (const fs::path& base : {root, root / "unified"}) {
      if (!fs::exists(base / "cgroup.controllers", ec)) continue;
      const fs::path dir = (base / fs::path(*path).relative_path()).lexically_normal();
      auto quota = TightestUpTo(base, dir, [](const fs::path& d) -> std::optional<double> {
        auto text = ReadFile(d / "cpu.max");
        return text ? ParseCgroupV2CpuMax(*text) : std::nullopt;
      });
      if (quota) return quota;
    }
  }
  if (auto path = CgroupPath(*self, false)) {
    for (const char* controller : {"cpu", "cpu,cpuacct", "cpuacct,cpu"}) {
      const fs::path base = root / controller;
      if (!fs::exists(base / "cpu.cfs_quota_us", ec)) continue;
      // In a container the v1 hierarchy is often mounted at its own cgroup: try the path, then the mount.
      const fs::path dir = (base / fs::path(*path).relative_path()).lexically_normal();
      auto read = [](const fs::path& d) -> std::optional<double> {
        auto q = ReadFile(d / "cpu.cfs_quota_us"), p = ReadFile(d / "cpu.cfs_period_us");
        return q && p ? ParseCgroupV1Quota(*q, *p) : std::nullopt;
      };
      auto quota = fs::exists(dir / "cpu.cfs_quota_us", ec) ? TightestUpTo(base, dir, read) : read(base);
      if (quota) return quota;
    }
  }
  return std::nullopt;
}

int UsableCpus(int affinity_cpus, std::optional<double> quota) {
  int cpus = std::max(1, affinity_cpus);
  if (quota && *quota > 0) cpus = std::min(cpus, static_cast<int>(std::ceil(*quota - 1e-9)));
  return std::max(1, cpus);
}

int ProcessCpus() {
  int affinity = 0;
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) affinity = CPU_COUNT(&set);
  if (affinity <= 0) affinity = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return UsableCpus(affinity, CgroupCpuQuota());
}

}  // namespace glimpse::server
