// A record bound to a model's signals: what every evaluator, the fit, selection and simulation
// read. Made by bind_record.hpp; it lives in records/ because operators/ reads records, not the
// other way round.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "runtime/records/column.hpp"

namespace sidc {

// One record's signals on one uniform time grid.
struct SampledRecord {
  std::string path;                                    // for messages
  double step = 0;
  Column time;                                         // absolute times, time[k] = time[0] + k*step
  std::map<std::string, Column> signals;               // by signal name (columns.hpp: owned or borrowed)
  std::map<std::string, std::string> columns;          // signal -> the column it came from (for messages)
  std::vector<double> weights;                         // eq. 2-1.6: per sample; empty = all 1
  std::string weights_column;
};

}  // namespace sidc
