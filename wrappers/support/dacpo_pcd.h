/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_pcd.h
 * \brief Minimal PCD (PCL's point cloud format) input/output in plain C, for the
 *        tools that do not link PCL (pcl_dacpo_orient_mpi).
 *
 * Reads `DATA ascii`, `binary` and `binary_compressed` (LZF, what
 * pcl::io::savePCDFileBinaryCompressed and pcl_dacpo_orient write) PCD files
 * of versions 0.6 and 0.7: the fields x, y, z are needed, normal_x, normal_y,
 * normal_z are optional, every other field (any TYPE I/U/F of SIZE 1, 2, 4 or
 * 8 and any COUNT, padding `_` fields too) is skipped. Values are converted to
 * float; NaN points of organized clouds are passed on as NaN (the caller
 * decides).
 * Writes `DATA binary` with float x y z [normal_x normal_y normal_z], WIDTH n,
 * HEIGHT 1: what pcl::io::loadPCDFile and pcl_viewer read.
 *
 * Uses dacpo_ply_cloud and the DACPO_PLY_* return codes of dacpo_ply.h, so one
 * caller handles both formats; dacpo_points_read / dacpo_points_write choose
 * by the file's extension (.pcd, otherwise PLY). Bad input returns an error
 * code and a message; nothing here crashes, prints or aborts.
 */
#ifndef DACPO_PCD_H
#define DACPO_PCD_H

#include "dacpo_ply.h"

#ifdef __cplusplus
extern "C" {
#endif

/** \brief Read a PCD file (see the file comment); \a out as in dacpo_ply_read(). */
int
dacpo_pcd_read(const char* path, dacpo_ply_cloud* out, char* err, size_t errlen);

/** \brief Write n points as binary PCD; arguments as in dacpo_ply_write() (the
 *  comment becomes `#` lines after the first header line). */
int
dacpo_pcd_write(const char* path,
                const float* xyz,
                const float* normals,
                size_t n,
                const char* comment,
                char* err,
                size_t errlen);

/** \brief 1 if \a path ends in ".pcd" (any case), else 0. */
int
dacpo_is_pcd_path(const char* path);

/** \brief 1 if \a path ends in ".ply" (any case), else 0. */
int
dacpo_is_ply_path(const char* path);

/** \brief dacpo_pcd_read() for a .pcd path, dacpo_ply_read() otherwise. */
int
dacpo_points_read(const char* path, dacpo_ply_cloud* out, char* err, size_t errlen);

/** \brief dacpo_pcd_write() for a .pcd path, dacpo_ply_write() otherwise. */
int
dacpo_points_write(const char* path,
                   const float* xyz,
                   const float* normals,
                   size_t n,
                   const char* comment,
                   char* err,
                   size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* DACPO_PCD_H */
