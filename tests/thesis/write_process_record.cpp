// Writes a synthetic section 4-2 record (process_record.hpp) as CSV on standard output:
//   build/tests/thesis/write_process_record > examples/thesis-4-2/process_record.csv
//   build/tests/thesis/write_process_record held > examples/thesis-4-2/process_held_record.csv
#include <cstdio>
#include <cstring>

#include "process_record.hpp"

int main(int argc, char** argv) {
  const bool held = argc == 2 && std::strcmp(argv[1], "held") == 0;
  if (argc > 2 || (argc == 2 && !held)) {
    std::fprintf(stderr, "usage: write_process_record [held]\n");
    return 2;
  }
  const auto r = held ? sidc::thesis::process_held_record() : sidc::thesis::process_record();
  std::fputs(sidc::thesis::process_record_csv(r).c_str(), stdout);
  return 0;
}
