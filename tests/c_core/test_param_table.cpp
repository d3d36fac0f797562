// SPDX-License-Identifier: BSD-3-Clause
// The parameter table (dacpo_param_table.h) is the one place a parameter's
// default is written: every field of dacpo_params is a row of it (viewpoint
// aside), and dacpo_params_init() gives the table's defaults.
#include <dacpo/dacpo.h>
#include <dacpo/dacpo_param_table.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <vector>

namespace {

struct Field {
  size_t offset, size, align;
  const char* name;
};

std::vector<Field>
tableFields()
{
  std::vector<Field> f;
#define DACPO_PARAM(kind, name, def, who)                                                     \
  f.push_back({offsetof(dacpo_params, name), sizeof(dacpo_params::name),                      \
               alignof(decltype(dacpo_params::name)), #name});
  DACPO_PARAMS()
#undef DACPO_PARAM
  f.push_back({offsetof(dacpo_params, viewpoint), sizeof(dacpo_params::viewpoint),
               alignof(double), "viewpoint"});
  return f;
}

} // namespace

// Sorted by offset, each field starts where the one before ends (plus the
// padding its alignment needs), and the last ends the struct: a field added to
// dacpo_params without a row leaves a hole and fails here.
TEST(DacpoParamTable, EveryFieldIsARow)
{
  std::vector<Field> f = tableFields();
  std::sort(f.begin(), f.end(), [](const Field& a, const Field& b) { return a.offset < b.offset; });
  size_t end = 0;
  for (const Field& x : f) {
    const size_t expect = (end + x.align - 1) / x.align * x.align;
    EXPECT_EQ(x.offset, expect) << "a field before " << x.name << " has no row in the table";
    end = x.offset + x.size;
  }
  EXPECT_LE(sizeof(dacpo_params) - end, alignof(dacpo_params)) << "a field after the last row";
}

// dacpo_params_init() gives each row's default, written in the table only.
TEST(DacpoParamTable, InitGivesTheTableDefaults)
{
  dacpo_params p;
  dacpo_params_init(&p);
#define DACPO_PARAM(kind, name, def, who)                                                     \
  EXPECT_EQ(p.name, static_cast<decltype(p.name)>(def)) << #name;
  DACPO_PARAMS()
#undef DACPO_PARAM
  EXPECT_EQ(p.viewpoint[0], 0.0);
  char msg[256] = "";
  EXPECT_EQ(dacpo_params_validate(&p, msg, sizeof(msg)), DACPO_OK) << msg;
}
