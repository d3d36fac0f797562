/* SPDX-License-Identifier: BSD-3-Clause */
/* Shared by the pcl_dacpo_* tools: a PCD or PLY file's own structure checked
 * before PCL parses it (PCL's readers crash or read past the end on some
 * malformed files), and the size a binary PLY must have. The headers are
 * parsed by the support library (dacpo_pcd_read_header, dacpo_ply_read_header);
 * the code is in dacpo_tool_file_checks.cpp (library dacpo_tool_io); tools only
 * (not installed). */
#pragma once

#include "dacpo_tool_options.h"

#include <cstdio>
#include <string>

namespace dacpo_tool {

/** Checks the file's own structure before PCL parses it. PCD: the header
 *  (dacpo_pcd_read_header), WIDTH x HEIGHT = POINTS, then the data: binary
 *  with no leading line PCL's reader takes for a header line that changes
 *  the layout (FIELDS, COLUMNS, SIZE, ...; DATA lines move the data as PCL
 *  does) and long enough, compressed sizes that agree with the header and
 *  the file, ASCII lines of numbers (PCL 1.13's reader crashes on files that
 *  are not PCD and turns words into NaN). PLY: the header
 *  (dacpo_ply_read_header) and what PCL 1.13's reader makes of it (it
 *  aborts on an obj_info line with a blank in front, on obj_info num_cols x
 *  num_rows below the vertex count, on uchar green/blue without red; so
 *  num_cols x num_rows must be the vertex count or the range_grid's rows,
 *  uchar red, green, blue a run), element counts the file can hold (PCL
 *  allocates what the header claims before reading), for ASCII every value
 *  of every element line a number, and the lists PCL stores: a vertex list
 *  no longer than in vertex 0, a mapped range_grid row's index a vertex.
 *  On failure returns false with "'path' is not a valid KIND file: line N:
 *  why" in \a error. */
bool
checkCloudFile(const std::string& path, long long file_size, std::string& error);

/** Size a binary PLY must have: its header plus the bytes of every element's
 *  rows (list rows walked one by one; dacpo_ply_binary_size). 0 if that cannot
 *  be told (ASCII, a bad header, data that ends early). */
long long
expectedBinaryPlySize(const std::string& path);

} // namespace dacpo_tool
