/* SPDX-License-Identifier: BSD-3-Clause */
/* Explicit instantiations of pcl::DACPONormalOrientation for the common point
 * types. Other types: define PCL_NO_PRECOMPILE before including the header, or
 * include <pcl_dacpo/impl/dacpo_normal_orientation.hpp> and use
 * PCL_INSTANTIATE_DACPONormalOrientation(T, OutT). The list is kept short on
 * purpose: every pair costs compile time. */
#include <pcl_dacpo/dacpo_normal_orientation.h>
#include <pcl_dacpo/impl/dacpo_normal_orientation.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

// clang-format off
PCL_INSTANTIATE_PRODUCT(DACPONormalOrientation,
                        ((pcl::PointXYZ)(pcl::PointXYZRGB)(pcl::PointXYZRGBA)(pcl::PointXYZI)
                         (pcl::PointNormal)(pcl::PointXYZRGBNormal)(pcl::PointXYZINormal))
                        ((pcl::Normal)(pcl::PointNormal)(pcl::PointXYZRGBNormal)
                         (pcl::PointXYZINormal)))
// clang-format on
