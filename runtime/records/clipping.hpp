// A clipped output: a sensor at the end of its range (an amplifier or converter saturated) writes
// its rail value for as long as the signal stays beyond it. There the record is not the system's
// output, the model's equations do not hold, and a fit over those samples is biased however good
// the model: the user should know, and fit a window without them.
//
// Method. A clipped signal repeats its largest (or smallest) value exactly in runs of neighbouring
// samples, which an unclipped signal does not. Found when
//   1. at least 3 samples equal to the signal's largest (smallest) value lie in runs of 2 or more,
//      one run at least 3 long (a peak sampled symmetrically and rounded repeats its top twice);
//   2. elsewhere fewer than 1% of neighbouring pairs repeat a value (a coarsely quantised signal,
//      or one that settles exactly, repeats values everywhere: its extreme runs prove nothing);
//   3. the signal arrives at a run at speed: some run's entering or leaving difference exceeds a
//      tenth of the median absolute difference of neighbouring samples (a response that settles
//      exactly, or a smooth turning point, reaches its extreme with a difference near 0).
// Reported (the driver calls clipped_outputs for every recorded output); what to do is the user's
// choice: a window without the runs, `--split-at-gaps` (which cuts them out like faulty cells:
// bind_record.hpp, unbroken_stretches), or a model of the saturation.
//
// Relies on: nothing. Guarantees: no exceptions; O(n) time, O(1) extra memory beyond a copy of
// the differences for their median (at most kMaxMedianSamples, evenly spaced).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "ir/ir.hpp"
#include "runtime/records/sampled_record.hpp"

namespace sidc {

struct ClippedSide {
  bool found = false;
  double value = 0;          // the rail: the signal's largest (or smallest) value
  std::size_t samples = 0;   // samples at it in runs of 2 or more
  std::size_t runs = 0;
  std::size_t first = 0;     // the first and the last such sample
  std::size_t last = 0;
};

struct Clipping {
  std::string record, signal;
  double step = 0;
  double first_time = 0, last_time = 0;  // the first sample of the first run and the last of the last (either side)
  ClippedSide top, bottom;
  bool found() const { return top.found || bottom.found; }
};

// The clipping of `y` (uniformly sampled; a non-finite sample, a faulty cell, is skipped and breaks
// a run); its record and signal names left empty.
Clipping find_clipping(std::span<const double> y);

// Per sample, 1 where `y` sits at a rail find_clipping found (in a run of 2 or more); empty when
// none was found. `--split-at-gaps` cuts these samples out like faulty cells.
std::vector<char> clipped_samples(std::span<const double> y);

// Every recorded output of a dynamic `model` in `record` examined; one entry per clipped output.
std::vector<Clipping> clipped_outputs(const SampledRecord& record, const ir::Model& model);

}  // namespace sidc
