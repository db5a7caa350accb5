#pragma once
// Times are seconds in doubles. Two times closer than kTimeTolerance are the same instant: a
// sample stamped at an image's capture time is "at or before" it however the two stamps were
// rounded (1 ns: far below any sensor's period, far above a double's rounding of 1e9 s).

namespace inhand {

constexpr double kTimeTolerance = 1e-9;  // [s]

}  // namespace inhand
