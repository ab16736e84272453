#pragma once
// The original simulator exchanges every number as a 32-bit float printed with 7
// significant digits. These functions give the value a number has after that trip, so the
// in-process loop sees exactly what a planner on the wire sees.

namespace overtake::core {

/// The double that a planner parses from the simulator's text for `value`: rounded to a
/// 32-bit float, then to 7 significant decimal digits. Idempotent. NaN and infinities pass
/// through unchanged.
[[nodiscard]] double wire_round(double value);

}  // namespace overtake::core
