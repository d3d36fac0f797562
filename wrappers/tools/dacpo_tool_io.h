/* SPDX-License-Identifier: BSD-3-Clause */
/* Shared by the pcl_dacpo_* tools: load and save pcl::PCLPointCloud2 by
 * extension with clear errors (the file checked first), every output written
 * through a temporary file, checked, synced and renamed. Includes the other
 * tool headers: options (dacpo_tool_options.h), file checks
 * (dacpo_tool_file_checks.h) and fields (dacpo_tool_fields.h). The template
 * writeAtomically is here, the rest in dacpo_tool_io.cpp (library
 * dacpo_tool_io); tools only (not installed). */
#pragma once

#include "dacpo_tool_fields.h"
#include "dacpo_tool_file_checks.h"
#include "dacpo_tool_options.h"

#include "dacpo_cleanup.h"
#include "dacpo_paths.h"
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/point_types.h>

#include <sys/stat.h>

#include <algorithm>
#include <exception>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <limits>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace dacpo_tool {

/** Loads a .pcd or .ply into \a cloud and checks it is complete and has x, y, z.
 *  On failure returns false with a message in \a error. */
bool
loadCloud2(const std::string& path, pcl::PCLPointCloud2& cloud, std::string& error);

/* ---- safe output -------------------------------------------------------
 * A tool never leaves a half-written file, nor destroys the one it replaces
 * (`pcl_dacpo_orient scan.ply scan.ply` on a full disk): every output goes to a
 * temporary file in the target's folder, is checked, synced to disk and only
 * then renamed over the target. PCL's writers do not report write errors (and
 * its PCD writer maps the file, which dies with SIGBUS on a full disk), so PCD
 * data is produced in memory and written here with every call checked, and
 * PLY files written by PCL are read back and their size checked. */

/** errno as text, with the path. */
std::string
ioError(const std::string& what, const std::string& path);

/** Writes \a bytes to \a path (created or truncated), checking every write,
 *  fsync and close; messages name \a shown (the file the user asked for). */
bool
writeAllChecked(const std::string& path,
                const std::string& bytes,
                std::string& error,
                const std::string& shown = std::string());

/** fsync of a file written by someone else (PCL). */
bool
syncFile(const std::string& path, std::string& error);

/** Produces \a path through a temporary file beside it: \a produce writes the
 *  temporary file (given its name), then it is synced and renamed over \a path.
 *  On any failure the temporary file is removed and \a path is untouched. */
template <typename Produce>
bool
writeAtomically(const std::string& path, Produce produce, std::string& error)
{
  char name[4352];
  if (dacpo_temp_sibling(path.c_str(), "tmp", static_cast<long>(::getpid()), name,
                         sizeof(name)) != 0) {
    error = "'" + path + "': name too long for a temporary file beside it";
    return false;
  }
  const std::string tmp = name;
  /* a SIGINT or SIGTERM while it is written removes it (dacpo_cleanup.h) */
  const int slot = dacpo_cleanup_add(tmp.c_str());
  const bool ok = produce(tmp, error) && syncFile(tmp, error);
  if (ok && std::rename(tmp.c_str(), path.c_str()) == 0) {
    dacpo_cleanup_drop(slot);
    return true;
  }
  if (ok)
    error = ioError("cannot replace", path);
  std::remove(tmp.c_str());
  dacpo_cleanup_drop(slot);
  return false;
}

/** Writes binary-compressed PCD or binary PLY by extension, safely (above). */
bool
saveCloud2(const std::string& path,
           const pcl::PCLPointCloud2& cloud,
           std::string& error);

} // namespace dacpo_tool
