// How many CPUs this process may actually use: the CPUs of its affinity mask (sched_getaffinity),
// bounded by its cgroup's CPU quota (v2 cpu.max, v1 cpu.cfs_quota_us / cpu.cfs_period_us). In a
// container limited to 2 CPUs on a 64-core node that is 2, where std::thread::hardware_concurrency()
// says 64. The parsers are pure so tests can feed them a cgroup's files.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace glimpse::server {

// cgroup v2 cpu.max ("max 100000" or "200000 100000"): quota / period in CPUs, nullopt for no limit
// or text that is not such a line.
std::optional<double> ParseCgroupV2CpuMax(std::string_view text);
// cgroup v1 cpu.cfs_quota_us and cpu.cfs_period_us: quota / period, nullopt for -1 (no limit) or bad text.
std::optional<double> ParseCgroupV1Quota(std::string_view quota_us, std::string_view period_us);
// The cgroup path of this process for a v2 line "0::/path" or a v1 line "N:...cpu...:/path" of
// /proc/self/cgroup; nullopt when the text has no such line.
std::optional<std::string> CgroupPath(std::string_view proc_self_cgroup, bool v2);

// The tightest CPU quota of the process's cgroup and its ancestors under `root` (normally
// /sys/fs/cgroup), v2 first, then v1; nullopt when none is set.
std::optional<double> CgroupCpuQuota(const std::string& root = "/sys/fs/cgroup",
                                      const std::string& proc_self_cgroup = "/proc/self/cgroup");

// min(affinity CPUs, ceil(quota)), at least 1.
int UsableCpus(int affinity_cpus, std::optional<double> quota);

// UsableCpus of this process: sched_getaffinity and CgroupCpuQuota(); falls back on
// std::thread::hardware_concurrency when the affinity cannot be read.
int ProcessCpus();

}  // namespace glimpse::server
