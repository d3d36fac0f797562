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
#define DACPO_PARAM(kind, type, name, def, who, cli, flag, doc)                                                     \
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
#define DACPO_PARAM(kind, type, name, def, who, cli, flag, doc)                                                     \
  EXPECT_EQ(p.name, static_cast<decltype(p.name)>(def)) << #name;
  DACPO_PARAMS()
#undef DACPO_PARAM
  EXPECT_EQ(p.viewpoint[0], 0.0);
  char msg[256] = "";
  EXPECT_EQ(dacpo_params_validate(&p, msg, sizeof(msg)), DACPO_OK) << msg;
}

// dacpo_params_set takes every row by its name: numbers for numeric kinds, the
// value's name for enums.
TEST(DacpoParamsSet, EveryRowIsSettableByName)
{
  dacpo_params p;
  dacpo_params_init(&p);
  char msg[256] = "";
  size_t rows = 0;
#define DACPO_PARAM(kind, type, name, def, who, cli, flag, doc)                                     \
  ++rows;                                                                                     \
  EXPECT_EQ(dacpo_params_set(&p, #name, std::strcmp(#kind, "ENUM") ? "1" : "XX", msg,        \
                             sizeof(msg)),                                                    \
            std::strcmp(#kind, "ENUM") ? DACPO_OK : DACPO_ERR_INVALID_ARGUMENT)               \
      << #name << ": " << msg;
  DACPO_PARAMS()
#undef DACPO_PARAM
  EXPECT_GE(rows, 30u);
}

TEST(DacpoParamsSet, KnownValues)
{
  dacpo_params p;
  dacpo_params_init(&p);
  char msg[256] = "";
  ASSERT_EQ(dacpo_params_set(&p, "dipole_c", "2.5", msg, sizeof(msg)), DACPO_OK) << msg;
  EXPECT_EQ(p.dipole_c, 2.5);
  ASSERT_EQ(dacpo_params_set(&p, "dipole_c", "-1", msg, sizeof(msg)), DACPO_OK) << msg;
  EXPECT_EQ(p.dipole_c, -1.0);
  ASSERT_EQ(dacpo_params_set(&p, "k", "16", msg, sizeof(msg)), DACPO_OK) << msg;
  EXPECT_EQ(p.k, 16u);
  ASSERT_EQ(dacpo_params_set(&p, "seed", "18446744073709551615", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.seed, UINT64_MAX);
  ASSERT_EQ(dacpo_params_set(&p, "edge_weight", "overlap", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.edge_weight, DACPO_WEIGHT_OVERLAP);
  ASSERT_EQ(dacpo_params_set(&p, "disconnected", "bridge", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.disconnected, DACPO_DISCONNECTED_BRIDGE);
  ASSERT_EQ(dacpo_params_set(&p, "sign_policy", "keep", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.sign_policy, DACPO_SIGN_KEEP);
  ASSERT_EQ(dacpo_params_set(&p, "scan_kind", "single", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.scan_kind, DACPO_SCAN_SINGLE_VIEW);
  ASSERT_EQ(dacpo_params_set(&p, "ipsr_enabled", "0", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.ipsr_enabled, 0);
}

// A value the field cannot hold, or an unknown name, is refused with a message
// naming it, and nothing changes.
TEST(DacpoParamsSet, BadValuesLeaveTheParamsAsTheyWere)
{
  dacpo_params p, before;
  dacpo_params_init(&p);
  before = p;
  char msg[256] = "";
  const char* bad[][2] = {{"k", "-1"},           {"k", "ten"},          {"k", ""},
                          {"k", " 5"},           {"k", "5x"},           {"dipole_c", "nan"},
                          {"dipole_c", "inf"},   {"dipole_c", "1,5"},   {"ipsr_enabled", "2"},
                          {"num_threads", "4294967296"}, {"dipole_final_sweep", "2147483648"},
                          {"seed", "18446744073709551616"}, {"edge_weight", "VCR"},
                          {"scan_kind", "1"}};
  for (const auto& b : bad) {
    EXPECT_EQ(dacpo_params_set(&p, b[0], b[1], msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT)
        << b[0] << "=" << b[1];
    EXPECT_NE(std::strstr(msg, b[0]), nullptr) << msg;
    EXPECT_EQ(std::memcmp(&p, &before, sizeof(p)), 0) << b[0] << "=" << b[1];
  }
  EXPECT_EQ(dacpo_params_set(&p, "dipole_cc", "1", msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::strstr(msg, "dipole_cc"), nullptr) << msg;
  EXPECT_EQ(dacpo_params_set(&p, "viewpoint", "1", msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_params_set(nullptr, "k", "1", msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_params_set(&p, "k", nullptr, nullptr, 0), DACPO_ERR_INVALID_ARGUMENT);
}
