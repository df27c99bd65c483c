// local.csv (report/fit_files.hpp, issue 18) from a LocalFitSummary made by hand: the columns,
// shortest round-trip numbers, empty cells for a rank-deficient window (never "nan"), a `record`
// column quoted as RFC 4180 has it when a path holds a comma, and one group's columns after another.
#include <gtest/gtest.h>

#include <sstream>

#include "report/fit_files.hpp"

namespace sidc {
namespace {

LocalRecordFit windows(const std::string& path, double t0) {
  LocalRecordFit r;
  r.path = path;
  r.window_samples = 10;
  r.t_center = {t0, t0 + 0.5};
  r.G = {0.25, std::numeric_limits<double>::quiet_NaN()};
  r.n = {20, 20};
  r.rank = {2, 1};  // the second window rank deficient: no estimate
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r.estimates = {1.5, -2, nan, nan};
  r.standard_errors = {0.1, 0.125, nan, nan};
  return r;
}

TEST(LocalCsv, ColumnsNumbersAndRankDeficientWindows) {
  LocalFitSummary s;
  LocalGroupFit g;
  g.columns = {"a", "c[1]"};
  g.records = {windows("one.csv", 1)};
  s.groups = {g};
  std::ostringstream out;
  ASSERT_TRUE(write_local_csv(out, s));
  EXPECT_EQ(out.str(),
            "t_center,a,a_se,c[1],c[1]_se,G,n,rank\n"
            "1,1.5,0.1,-2,0.125,0.25,20,2\n"
            "1.5,,,,,,20,1\n");
}

TEST(LocalCsv, SeveralRecordsAndGroups) {
  LocalFitSummary s;
  LocalGroupFit g1, g2;
  g1.columns = {"a", "b"};
  g2.columns = {"k", "m"};
  g1.records = {windows("one.csv", 1), windows("with,comma \"q\".csv", 7)};
  g2.records = g1.records;
  s.groups = {g1, g2};
  std::ostringstream out;
  ASSERT_TRUE(write_local_csv(out, s));
  EXPECT_EQ(out.str(),
            "record,t_center,a,a_se,b,b_se,G_1,n_1,rank_1,k,k_se,m,m_se,G_2,n_2,rank_2\n"
            "one.csv,1,1.5,0.1,-2,0.125,0.25,20,2,1.5,0.1,-2,0.125,0.25,20,2\n"
            "one.csv,1.5,,,,,,20,1,,,,,,20,1\n"
            "\"with,comma \"\"q\"\".csv\",7,1.5,0.1,-2,0.125,0.25,20,2,1.5,0.1,-2,0.125,0.25,20,2\n"
            "\"with,comma \"\"q\"\".csv\",7.5,,,,,,20,1,,,,,,20,1\n");
}

}  // namespace
}  // namespace sidc
