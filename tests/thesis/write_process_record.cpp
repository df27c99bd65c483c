// Writes the synthetic section 4-2 record (process_record.hpp) as CSV on standard output:
//   build/tests/thesis/write_process_record > examples/thesis-4-2/process_record.csv
#include <cstdio>

#include "process_record.hpp"

int main() {
  const auto r = sidc::thesis::process_record();
  std::printf("t,x,y1,y2\n");
  for (std::size_t k = 0; k < r.t.size(); ++k) std::printf("%.2f,%.6f,%.6f,%.6f\n", r.t[k], r.x[k], r.y1[k], r.y2[k]);
  return 0;
}
