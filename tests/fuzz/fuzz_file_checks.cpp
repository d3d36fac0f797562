// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer target: the tools' file loading (dacpo_tool::loadCloud2: the
// structure checks of dacpo_tool_file_checks.cpp over the support library's
// header parsers, then PCL's reader when they pass) on arbitrary bytes named
// .pcd or .ply (first byte's low bit). Contract: no
// crash or sanitizer report; a failure comes with a message; a success is a
// cloud whose data size matches its header and which has x, y, z.
#include <pcl/console/print.h>

#include "dacpo_tool_io.h"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>

extern "C" int
LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  static const bool quiet = [] {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    return true;
  }();
  (void)quiet;
  if (size < 1)
    return 0;
  const std::string path = std::string("/tmp/dacpo_fuzz_") +
                           std::to_string(::getpid()) +
                           ((data[0] & 1) ? ".ply" : ".pcd");
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f)
    return 0;
  std::fwrite(data + 1, 1, size - 1, f);
  std::fclose(f);
  pcl::PCLPointCloud2 cloud;
  std::string error;
  const bool ok = dacpo_tool::loadCloud2(path, cloud, error);
  std::remove(path.c_str());
  if (!ok && error.empty())
    std::abort();
  if (ok && cloud.data.size() !=
                static_cast<std::size_t>(cloud.width) * cloud.height * cloud.point_step)
    std::abort();
  return 0;
}
