/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_ply.h
 * \brief Minimal PLY input/output for point clouds with normals (tests, tools).
 *
 * Writes binary little-endian PLY with vertex properties `float x y z` and, when
 * normals are given, `float nx ny nz` (the layout of the real-scan test files).
 * Reads ascii, binary_little_endian and binary_big_endian PLY: the vertex
 * element must have x, y, z; nx, ny, nz are optional; other vertex properties
 * (any scalar type, lists too) and other elements are skipped. Values of any
 * numeric type are converted to float.
 *
 * Bad input (missing file, garbage, bad header, truncated data, absurd counts)
 * returns an error code and a message; nothing here crashes, prints or aborts.
 * No global state: safe to call from several threads on different files.
 */
#ifndef DACPO_PLY_H
#define DACPO_PLY_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/** \brief Return codes of the PLY functions. */
enum {
  DACPO_PLY_OK = 0,
  DACPO_PLY_ERR_ARGUMENT = -1, /**< NULL pointer or bad argument */
  DACPO_PLY_ERR_MEMORY = -2,   /**< out of memory */
  DACPO_PLY_ERR_IO = -3,       /**< cannot open, read, write or close the file */
  DACPO_PLY_ERR_FORMAT = -4 /**< not a PLY, unsupported or bad header, truncated data */
};

/** \brief A point cloud read from a PLY file; free with dacpo_ply_cloud_free(). */
typedef struct dacpo_ply_cloud {
  size_t n;       /**< number of vertices */
  float* xyz;     /**< 3n coordinates (NULL when n == 0) */
  float* normals; /**< 3n normals, or NULL when the file has no nx, ny, nz */
  double* xyz_exact; /**< dacpo_ply_read_exact only: 3n coordinates as read when
                          float cannot hold them (double, 32-bit int), else NULL */
  double origin[3];  /**< xyz = xyz_exact - origin (vertex 0), 0 otherwise */
} dacpo_ply_cloud;

/**
 * \brief Write n points as binary little-endian PLY.
 * \param[in] path     output file (created or truncated)
 * \param[in] xyz      3n floats (may be NULL only when n == 0)
 * \param[in] normals  3n floats, or NULL to write positions only
 * \param[in] comment  text for `comment` header lines (one per line), or NULL
 * \param[out] err     message buffer (may be NULL)
 * \return DACPO_PLY_OK, DACPO_PLY_ERR_ARGUMENT or DACPO_PLY_ERR_IO.
 */
int
dacpo_ply_write(const char* path,
                const float* xyz,
                const float* normals,
                size_t n,
                const char* comment,
                char* err,
                size_t errlen);

/**
 * \brief Read the vertex positions (and normals when present) of a PLY file.
 * \param[out] out  zeroed first; owns the arrays on success, empty on failure
 * \return DACPO_PLY_OK or a negative DACPO_PLY_ERR_* code with a message in err.
 */
int
dacpo_ply_read(const char* path, dacpo_ply_cloud* out, char* err, size_t errlen);

/**
 * \brief As dacpo_ply_read, for files whose coordinates float cannot hold (a
 *  georeferenced double file): they are kept in xyz_exact, and xyz holds their
 *  offsets from vertex 0 (origin), where float keeps sub-millimetre steps.
 */
int
dacpo_ply_read_exact(const char* path, dacpo_ply_cloud* out, char* err, size_t errlen);

/**
 * \brief Write n points as binary little-endian PLY with double x y z (float
 *  normals): the coordinates of dacpo_ply_read_exact written back unchanged.
 */
int
dacpo_ply_write_exact(const char* path,
                      const double* xyz,
                      const float* normals,
                      size_t n,
                      const char* comment,
                      char* err,
                      size_t errlen);

/** \brief Where the vertex rows of a binary PLY lie, for reading any range of
 *  them without the rest (out-of-core and per-rank reading). Needs
 *  binary_little_endian or binary_big_endian and vertex rows of scalar
 *  properties only (no lists), so that every row has the same size. */
typedef struct dacpo_ply_rows {
  unsigned long long n;           /**< number of vertices */
  unsigned long long data_offset; /**< file offset of vertex 0 */
  size_t stride;                  /**< bytes per vertex row */
  size_t offset[3];               /**< x, y, z within a row */
  int type[3];                    /**< their scalar types (internal codes) */
  int swap;                       /**< 1: big-endian values */
  double origin[3]; /**< subtracted before the float conversion of
                         dacpo_ply_rows_read (0 after open; see set_origin) */
} dacpo_ply_rows;

/**
 * \brief Parse the header of path and locate its vertex rows.
 * \return DACPO_PLY_OK; DACPO_PLY_ERR_FORMAT with a message for ASCII files,
 *  list properties in the vertex element or truncated files; DACPO_PLY_ERR_IO.
 */
int
dacpo_ply_rows_open(const char* path, dacpo_ply_rows* out, char* err, size_t errlen);

/**
 * \brief Positions of vertices [first, first + count) into xyz (3 count floats),
 *  read from f (opened "rb" on the same file) at their offsets.
 * \return DACPO_PLY_OK, DACPO_PLY_ERR_ARGUMENT (range beyond n), or
 *  DACPO_PLY_ERR_IO (short read).
 */
int
dacpo_ply_rows_read(FILE* f,
                    const dacpo_ply_rows* rows,
                    unsigned long long first,
                    size_t count,
                    float* xyz,
                    char* err,
                    size_t errlen);

/** \brief As dacpo_ply_rows_read, the exact values as double (origin not applied). */
int
dacpo_ply_rows_read_double(FILE* f,
                           const dacpo_ply_rows* rows,
                           unsigned long long first,
                           size_t count,
                           double* xyz,
                           char* err,
                           size_t errlen);

/** \brief The x, y, z bytes of each row as stored, turned little-endian
 *  (dacpo_ply_rows_xyz_bytes per row): an output keeps the input's coordinates
 *  bit for bit whatever their type. */
int
dacpo_ply_rows_read_raw(FILE* f,
                        const dacpo_ply_rows* rows,
                        unsigned long long first,
                        size_t count,
                        unsigned char* out,
                        char* err,
                        size_t errlen);

/** \brief Bytes of x, y and z in one row (12 for float coordinates). */
size_t
dacpo_ply_rows_xyz_bytes(const dacpo_ply_rows* rows);

/** \brief 1 when every coordinate type converts to float exactly (float and
 *  the 8/16-bit integers), 0 for double and 32-bit integers. */
int
dacpo_ply_rows_exact_in_float(const dacpo_ply_rows* rows);

/** \brief PLY type name of coordinate k (0 x, 1 y, 2 z), for an output header. */
const char*
dacpo_ply_rows_type_name(const dacpo_ply_rows* rows, int k);

/** \brief Sets rows->origin to vertex 0 when the coordinates are not exact in
 *  float (a georeferenced double file: floats of the offsets keep mm where
 *  floats of the coordinates lose decimetres), to 0 otherwise. */
int
dacpo_ply_rows_set_origin(FILE* f, dacpo_ply_rows* rows, char* err, size_t errlen);

/** \brief Formats of a PLY file (dacpo_ply_header_info.format). */
enum { DACPO_PLY_ASCII = 0, DACPO_PLY_BINARY_LE = 1, DACPO_PLY_BINARY_BE = 2 };

/** \brief Most elements, and properties per element, a PLY header may declare. */
#define DACPO_PLY_MAX_ELEMENTS 64
#define DACPO_PLY_MAX_PROPERTIES 256

/** \brief A property of a PLY element: a scalar, or a list. */
typedef struct dacpo_ply_property_info {
  unsigned char bytes;       /**< bytes of the scalar, or of each item of the list */
  unsigned char count_bytes; /**< bytes of the list's length; 0 for a scalar */
} dacpo_ply_property_info;

/** \brief An element of a PLY header. */
typedef struct dacpo_ply_element_info {
  char name[64];            /**< cut to 63 bytes */
  unsigned long long count; /**< rows */
  int nprops;
  dacpo_ply_property_info props[DACPO_PLY_MAX_PROPERTIES];
} dacpo_ply_element_info;

/** \brief What a PLY header declares (dacpo_ply_read_header); about 38 kB. */
typedef struct dacpo_ply_header_info {
  int format; /**< DACPO_PLY_ASCII, DACPO_PLY_BINARY_LE or DACPO_PLY_BINARY_BE */
  int nelements;
  dacpo_ply_element_info elements[DACPO_PLY_MAX_ELEMENTS];
  unsigned long long data_offset; /**< file offset of the first data byte */
  int lines; /**< header lines: end_header's line number, or the line of the error */
} dacpo_ply_header_info;

/**
 * \brief Read and check the header of a PLY file from \a f (at the file's
 *  start) through end_header: the one PLY header parser, of dacpo_ply_read()
 *  and of the pcl_dacpo_* tools' file checks.
 *
 * Checked: the first line is "ply"; a format line (ascii, binary_little_endian
 * or binary_big_endian); every line a comment, obj_info, format, element NAME
 * COUNT or property line with known types (a list's length an integer type)
 * without NUL bytes (lines over 4095 bytes are read cut to that); at most
 * 4096 lines, DACPO_PLY_MAX_ELEMENTS elements and DACPO_PLY_MAX_PROPERTIES
 * properties each. Not checked: the data.
 * \param[in] path  named in the message
 * \return DACPO_PLY_OK with \a f at the first data byte; DACPO_PLY_ERR_FORMAT
 *  with "'path' is not a valid PLY file: line N: why" (info->lines = N);
 *  DACPO_PLY_ERR_MEMORY or DACPO_PLY_ERR_IO.
 */
int
dacpo_ply_read_header(
    FILE* f, const char* path, dacpo_ply_header_info* info, char* err, size_t errlen);

/**
 * \brief The size a binary PLY file must have: its header and the rows of
 *  every element, rows with lists walked length by length (what a check of a
 *  written file compares with the file's size).
 * \return DACPO_PLY_OK with *bytes; DACPO_PLY_ERR_FORMAT (ASCII, a bad header,
 *  lists that run past the end) or DACPO_PLY_ERR_IO, *bytes = 0.
 */
int
dacpo_ply_binary_size(const char* path,
                      unsigned long long* bytes,
                      char* err,
                      size_t errlen);

/**
 * \brief The value at \a p of the PLY scalar type called \a type_name (char,
 *  uchar, int8 ... float64, as in a header), its bytes little-endian or, with
 *  \a big_endian, big-endian; 0 for a name that is no PLY type.
 */
double
dacpo_ply_decode_named(const unsigned char* p, const char* type_name, int big_endian);

/** \brief Free the arrays and zero the struct. NULL-safe, idempotent. */
void
dacpo_ply_cloud_free(dacpo_ply_cloud* cloud);

#ifdef __cplusplus
}
#endif

#endif /* DACPO_PLY_H */
