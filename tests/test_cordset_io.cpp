// The cord file as written (core/cordset_io.h): the values a reader sees beside the ones the
// program reads back.
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/cordset_io.h"
#include "core/diagnostics.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

using testing::TempDir;

TEST(CordSetFile, WritesAScaleAtItsBoundAsTheBoundAndKeepsTheRestLengthExact) {
  TempDir dir;
  CordSet set;
  set.tips.push_back({"anterolateral", Eigen::Vector3d(0, 5, -20), std::nullopt});
  Cord cord;
  cord.vertex = 0;
  cord.seed_rest_length = 24.86070378370099;
  cord.rest_length = 0.7 * cord.seed_rest_length;            // a fit's scale at its lower bound
  ASSERT_NE(cord.rest_length / cord.seed_rest_length, 0.7);  // the ratio this test is about
  set.cords.push_back(cord);
  writeCordSet(dir / "cords.json", set);

  std::ifstream in(dir / "cords.json");
  const nlohmann::json written = nlohmann::json::parse(in);
  EXPECT_EQ(written["cords"][0]["scale"].get<double>(), 0.7);

  CordSet read;
  Diagnostics diagnostics;
  ASSERT_TRUE(readCordSet(dir / "cords.json", "cords.json", read, diagnostics));
  EXPECT_EQ(read.cords[0].rest_length, cord.rest_length);  // bit for bit
}

}  // namespace
}  // namespace chordfit
