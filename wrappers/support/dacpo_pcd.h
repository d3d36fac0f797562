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

/** \brief Most fields a PCD header may list. */
#define DACPO_PCD_MAX_FIELDS 256

/** \brief One field of a PCD header. */
typedef struct dacpo_pcd_field {
  char name[64]; /**< cut to 63 bytes */
  int size;      /**< bytes per value: 1, 2, 4 or 8 */
  char type;     /**< 'I', 'U' or 'F' */
  size_t count;  /**< values per point (1 without a COUNT line) */
  size_t offset; /**< bytes from the start of a binary record */
} dacpo_pcd_field;

/** \brief What a PCD header declares (dacpo_pcd_read_header). */
typedef struct dacpo_pcd_header {
  dacpo_pcd_field f[DACPO_PCD_MAX_FIELDS];
  int nf;                       /**< fields */
  size_t points, width, height; /**< as given (0 when not) */
  int have_points, have_width, have_height;
  int have_size, have_type; /**< SIZE, TYPE given after the last FIELDS */
  char data[32];            /**< ascii, binary or binary_compressed */
  size_t record;            /**< bytes per point in binary data */
  int lines; /**< lines read: the DATA line's number, or the line of the error */
} dacpo_pcd_header;

/**
 * \brief Read and check the header of a PCD file from \a f (at the file's
 *  start) up to and including its DATA line; the one PCD header parser, of
 *  dacpo_pcd_read() and of the pcl_dacpo_* tools' file checks.
 *
 * Checked: the first line that is not blank is a comment, VERSION or FIELDS;
 * no line holds a NUL byte (lines over 4095 bytes are read cut to that); every
 * line is a comment or a known keyword with valid values (SIZE 1, 2, 4 or 8,
 * TYPE I, U or F, COUNT 1 to 1000000, one per field, after FIELDS; WIDTH,
 * HEIGHT, POINTS counts; at most DACPO_PCD_MAX_FIELDS fields); DATA is ascii,
 * binary or binary_compressed; FIELDS comes with SIZE and TYPE.
 * Not checked (the callers' choice): WIDTH, HEIGHT and POINTS against each
 * other and the file, which fields there are.
 * \param[in] path  named in the message
 * \return DACPO_PLY_OK with \a f at the first data byte; DACPO_PLY_ERR_FORMAT
 *  with "'path' is not a valid PCD file: line N: why" in err (h->lines = N).
 */
int
dacpo_pcd_read_header(
    FILE* f, const char* path, dacpo_pcd_header* h, char* err, size_t errlen);

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
