// SPDX-License-Identifier: BSD-3-Clause
// The space the frames saw through (input/dacpo_free_space.c) with known
// answers: a partition's two faces, one seen by frame 0, the other by frame
// 1. From the far face's own side its points are in plain view; from the near
// face's side the near face (frame 1) stands in the way; the frame's own
// points never do, nor anything within `skip` of either end.
#include <gtest/gtest.h>

#include <vector>

extern "C" {
#include "dacpo_free_space.h"
}

namespace {

// Two 1 m x 1 m faces on x = 0 (frame 0) and x = 0.1 (frame 1), 1 cm grid.
struct Partition {
  std::vector<double> xyz;
  std::vector<uint32_t> frame;
  Partition()
  {
    for (uint32_t f = 0; f < 2; ++f)
      for (int i = 0; i < 100; ++i)
        for (int j = 0; j < 100; ++j) {
          xyz.insert(xyz.end(), {0.1 * f, 0.01 * i, 0.01 * j});
          frame.push_back(f);
        }
  }
};

} // namespace

TEST(DacpoFreeSpace, OtherFramesStandInTheWayOwnPointsDoNot)
{
  Partition part;
  dacpo_free_space space{};
  dacpo_err err{};
  ASSERT_EQ(
      dacpo_free_space_make(
          part.xyz.data(), part.frame.size(), part.frame.data(), 0.015, &space, &err),
      DACPO_OK)
      << err.msg;
  const double p[3] = {0.0, 0.5, 0.5};     // a point of frame 0's face
  const double west[3] = {-1.5, 0.6, 0.4}; // its camera, on its own side
  const double east[3] = {1.5, 0.6, 0.4};  // the mirror image, behind frame 1's face
  EXPECT_EQ(dacpo_free_space_blocked(&space, p, west, 0.03, 0), 0);
  EXPECT_EQ(dacpo_free_space_blocked(&space, p, east, 0.03, 0), 1);
  // the same segment for a frame-1 point: its own face is no obstacle
  EXPECT_EQ(dacpo_free_space_blocked(&space, p, east, 0.03, 1), 0);
  // skipping past the near face (0.1 m away) leaves it out
  EXPECT_EQ(dacpo_free_space_blocked(&space, p, east, 0.2, 0), 0);
  // a segment shorter than both skips, and one running outside the cells
  const double near[3] = {0.04, 0.5, 0.5};
  EXPECT_EQ(dacpo_free_space_blocked(&space, p, near, 0.03, 0), 0);
  const double far_out[3] = {-3.0, -2.0, 5.0};
  EXPECT_EQ(dacpo_free_space_blocked(&space, p, far_out, 0.03, 0), 0);
  // the box of the points: the mirror stands outside it, a point between the faces inside
  const double between[3] = {0.05, 0.5, 0.5};
  EXPECT_EQ(dacpo_free_space_inside(&space, between), 1);
  EXPECT_EQ(dacpo_free_space_inside(&space, east), 0);
  dacpo_free_space_free(&space);
  dacpo_free_space_free(&space); // twice is harmless
}

TEST(DacpoFreeSpace, BadArgumentsAndEmptyClouds)
{
  dacpo_free_space space{};
  dacpo_err err{};
  const double xyz[3] = {0, 0, 0};
  const uint32_t frame[1] = {0};
  EXPECT_EQ(dacpo_free_space_make(nullptr, 1, frame, 0.01, &space, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_free_space_make(xyz, 1, nullptr, 0.01, &space, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_free_space_make(xyz, 1, frame, 0.0, &space, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  ASSERT_EQ(dacpo_free_space_make(xyz, 0, frame, 0.01, &space, &err), DACPO_OK);
  const double a[3] = {0, 0, 0}, b[3] = {1, 1, 1};
  EXPECT_EQ(dacpo_free_space_blocked(&space, a, b, 0.01, 0), 0);
  dacpo_free_space_free(&space);
}
