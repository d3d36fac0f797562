/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_cleanup.h
 * \brief Temporary files of the tools removed when a signal stops the process.
 *
 * The tools write temporary files beside their outputs (the output before its
 * rename, tile and halo files of the out-of-core mode). Registered here, they
 * are unlinked when SIGINT, SIGTERM or SIGHUP arrives; the signal is then
 * raised again with its default action, so the exit status still says what
 * stopped the process. A SIGKILL cannot be caught: after one, the files stay
 * (their names start with '.' and carry the process id, see dacpo_paths.h).
 *
 * The handler only calls unlink(), which is async-signal-safe; paths are
 * copied into fixed slots when registered. Not for libraries: a tool calls
 * dacpo_cleanup_install() once from main().
 */
#ifndef DACPO_CLEANUP_H
#define DACPO_CLEANUP_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** \brief Installs the handlers (once; later calls do nothing). 0 or -1. */
int
dacpo_cleanup_install(void);

/** \brief Registers path; returns its slot, or -1 (too long, no free slot:
 *  the file is then only removed by the caller). */
int
dacpo_cleanup_add(const char* path);

/** \brief Registers the series "<prefix>.tile0" .. "<prefix>.tile<count-1>". */
int
dacpo_cleanup_add_series(const char* prefix, size_t count);

/** \brief Forgets a slot (the caller renamed or removed the file). -1: no-op. */
void
dacpo_cleanup_drop(int slot);

#ifdef __cplusplus
}
#endif

#endif /* DACPO_CLEANUP_H */
