// The CPUs a process may use: the cgroup files' parsers, a fake cgroup tree (v2 and v1) with a
// quota on an ancestor, and the bound the affinity mask and the quota put together.
#include <gtest/gtest.h>
#include <sched.h>

#include <filesystem>

#include "common/temp_dir.h"
#include "server/cpus.h"

namespace glimpse::server {
namespace {

namespace fs = std::filesystem;

TEST(Cpus, ParsesCgroupV2CpuMax) {
  EXPECT_EQ(ParseCgroupV2CpuMax("max 100000\n"), std::nullopt);
  EXPECT_DOUBLE_EQ(*ParseCgroupV2CpuMax("200000 100000\n"), 2.0);
  EXPECT_DOUBLE_EQ(*ParseCgroupV2CpuMax("150000 100000"), 1.5);
  EXPECT_EQ(ParseCgroupV2CpuMax(""), std::nullopt);
  EXPECT_EQ(ParseCgroupV2CpuMax("garbage"), std::nullopt);
  EXPECT_EQ(ParseCgroupV2CpuMax("0 100000"), std::nullopt);
}

TEST(Cpus, ParsesCgroupV1Quota) {
  EXPECT_EQ(ParseCgroupV1Quota("-1\n", "100000\n"), std::nullopt);
  EXPECT_DOUBLE_EQ(*ParseCgroupV1Quota("50000\n", "100000\n"), 0.5);
  EXPECT_DOUBLE_EQ(*ParseCgroupV1Quota("400000", "100000"), 4.0);
  EXPECT_EQ(ParseCgroupV1Quota("x", "100000"), std::nullopt);
}

TEST(Cpus, FindsTheProcessCgroupPath) {
  const std::string hybrid = "12:cpu,cpuacct:/docker/abc\n4:memory:/docker/abc\n0::/user.slice/app\n";
  EXPECT_EQ(CgroupPath(hybrid, true), "/user.slice/app");
  EXPECT_EQ(CgroupPath(hybrid, false), "/docker/abc");
  EXPECT_EQ(CgroupPath("0::/\n", false), std::nullopt);
  EXPECT_EQ(CgroupPath("", true), std::nullopt);
  EXPECT_EQ(CgroupPath("3:cpuacct:/x\n", false), std::nullopt);  // cpuacct is not cpu
}

TEST(Cpus, UsableCpusIsTheTighterOfAffinityAndQuota) {
  EXPECT_EQ(UsableCpus(64, 2.0), 2);    // a 2-CPU container on a 64-core node
  EXPECT_EQ(UsableCpus(64, 1.5), 2);    // a fraction of a CPU still needs a thread
  EXPECT_EQ(UsableCpus(64, 0.25), 1);
  EXPECT_EQ(UsableCpus(4, 16.0), 4);    // affinity tighter than the quota
  EXPECT_EQ(UsableCpus(8, std::nullopt), 8);
  EXPECT_EQ(UsableCpus(0, std::nullopt), 1);
}

class FakeCgroup : public ::testing::Test {
 protected:
  void Write(const fs::path& relative, const std::string& text) { dir_.Write(relative.string(), text); }
  glimpse::testing::TempDir dir_{"cpus"};
  fs::path root_ = dir_.path();
};

TEST_F(FakeCgroup, V2QuotaOnAnAncestorBoundsTheProcess) {
  Write("cgroup.controllers", "cpu memory\n");
  Write("kubepods/cpu.max", "300000 100000\n");
  Write("kubepods/pod1/cpu.max", "max 100000\n");
  Write("proc_self_cgroup", "0::/kubepods/pod1\n");
  EXPECT_DOUBLE_EQ(*CgroupCpuQuota(root_.string(), (root_ / "proc_self_cgroup").string()), 3.0);
  Write("kubepods/pod1/cpu.max", "150000 100000\n");  // a child tighter than its parent
  EXPECT_DOUBLE_EQ(*CgroupCpuQuota(root_.string(), (root_ / "proc_self_cgroup").string()), 1.5);
}

TEST_F(FakeCgroup, V1QuotaAtTheMountOrThePath) {
  Write("cpu,cpuacct/cpu.cfs_quota_us", "200000\n");  // a container sees its own cgroup at the mount
  Write("cpu,cpuacct/cpu.cfs_period_us", "100000\n");
  Write("proc_self_cgroup", "5:cpu,cpuacct:/docker/abc\n0::/\n");
  EXPECT_DOUBLE_EQ(*CgroupCpuQuota(root_.string(), (root_ / "proc_self_cgroup").string()), 2.0);
  Write("cpu,cpuacct/docker/abc/cpu.cfs_quota_us", "50000\n");  // the host's view: the path exists
  Write("cpu,cpuacct/docker/abc/cpu.cfs_period_us", "100000\n");
  EXPECT_DOUBLE_EQ(*CgroupCpuQuota(root_.string(), (root_ / "proc_self_cgroup").string()), 0.5);
}

TEST_F(FakeCgroup, NoQuotaAnywhere) {
  Write("cgroup.controllers", "cpu\n");
  Write("cpu.max", "max 100000\n");
  Write("proc_self_cgroup", "0::/\n");
  EXPECT_EQ(CgroupCpuQuota(root_.string(), (root_ / "proc_self_cgroup").string()), std::nullopt);
  EXPECT_EQ(CgroupCpuQuota(root_.string(), (root_ / "missing").string()), std::nullopt);
}

TEST(Cpus, ThisProcessHasAtLeastOneAndNoMoreThanTheAffinity) {
  const int cpus = ProcessCpus();
  EXPECT_GE(cpus, 1);
  cpu_set_t set;
  CPU_ZERO(&set);
  ASSERT_EQ(sched_getaffinity(0, sizeof set, &set), 0);
  EXPECT_LE(cpus, CPU_COUNT(&set));
}

}  // namespace
}  // namespace glimpse::server
