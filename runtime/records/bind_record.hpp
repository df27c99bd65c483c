// A record read from a file, bound to a model's signals on one uniform time grid.
//
// Relies on: runtime/records/records.hpp (the file as columns) and the compiled model's data statement.
// Guarantees: the time column (the one bound to `t`, else a column named `t` or `time`, else a
// given step; a static model's rows are simply numbered) is uniformly sampled within tolerance, or the first bad row is named (`--resample`
// interpolates onto a uniform grid instead); every signal without a definition is a complete
// column; `every` keeps every k-th sample (the thesis' Delta = 0.020 from its Delta = 0.010 record);
// inputs given as expressions of t are evaluated on the grid.
#pragma once

#include <optional>
#include <variant>

#include "ir/ir.hpp"
#include "runtime/records/records.hpp"
#include "runtime/records/sampled_record.hpp"
#include "runtime/records/sampling.hpp"

namespace sidc {

struct BindOptions {
  std::optional<double> step;      // sampling step when the record has no time column
  std::optional<double> resample;  // interpolate linearly onto this step
  int every = 1;                   // decimation
  std::optional<std::string> weights;  // column of row weights (eq. 2-1.6)
  UniformStepOptions uniform;
};

std::variant<SampledRecord, Diagnostic> bind_record(const Record& record, const ir::DataSource& source,
                                                    const ir::Model& model, const BindOptions& options);

// A record with gaps (`--split-at-gaps`): the longest stretches of rows on which it can be bound,
// each of uniform time step with every column the model reads (time, signals, weights) a finite
// number. A stretch ends where a row has a faulty cell in such a column (the row is left out) or
// where the spacing of times leaves the tolerance of the median spacing of the record (a missing
// sample, a clock jump, a repeated or backward time); a dynamic model's output that looks clipped
// (clipping.hpp) has its samples at the rail left out like faulty cells. Stretches shorter than `min_rows` are
// returned in `short_ones`, not in `kept`. A record without a time column, or whose times are all
// faulty, is an error (nothing tells where a gap is).
struct Stretches {
  std::vector<IndexRange> kept;
  std::vector<IndexRange> short_ones;
  std::size_t rows_left_out = 0;  // rows with a faulty cell, or where a clipped output sits at its rail
  std::size_t rows_clipped = 0;   // of those, the clipped ones (clipping.hpp)
};
std::variant<Stretches, Diagnostic> unbroken_stretches(const Record& record, const ir::DataSource& source, const ir::Model& model,
                                                       const BindOptions& options, std::size_t min_rows);

// The same on a record the caller gives away: the columns used once are moved into the
// SampledRecord, not copied (the record is left with those columns empty).
std::variant<SampledRecord, Diagnostic> bind_record(Record&& record, const ir::DataSource& source, const ir::Model& model,
                                                    const BindOptions& options);

}  // namespace sidc
