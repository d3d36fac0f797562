/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_paths.h
 * \brief Output paths of the tools: checked before any work, and the names of
 *  the temporary files written beside them.
 *
 * Every tool writes a temporary sibling of its output and renames it onto the
 * output at the end, so that a failed or interrupted run never leaves a partial
 * file under the user's name. These helpers make the two promises that needs:
 * the folder exists and is writable (said before the work starts, not after),
 * and a temporary name is never the output itself (a name too long for a
 * sibling fails here, instead of being truncated to the target).
 */
#ifndef DACPO_PATHS_H
#define DACPO_PATHS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/**
 * \brief 0 when a file can be written at path through a temporary sibling:
 *  its folder exists, is a folder and is writable, path is not a folder, and a
 *  sibling name (dacpo_temp_sibling) fits the system's name limits.
 * \return 0, or -1 with a message naming the path and the reason.
 */
int
dacpo_output_path_check(const char* path, char* err, size_t errlen);

/**
 * \brief The temporary sibling of path: "<dir>/.<name>.<tag><id><ext>" (tag
 *  e.g. "tmp", id the process id, or rank 0's under MPI, ext the target's own
 *  extension, so writers that go by the name write its format), never equal
 *  to path.
 * \return 0, or -1 (buf holds "") when the name does not fit cap, PATH_MAX or
 *  NAME_MAX.
 */
int
dacpo_temp_sibling(const char* path, const char* tag, long id, char* buf, size_t cap);

#ifdef __cplusplus
}
#endif

#endif /* DACPO_PATHS_H */
