#pragma once
// The progress lines of the batch commands (bench, hunt, risk, tune) as text, for a terminal's
// status line (base::StatusLine) or a log.

#include <string>

#include "overtake/batch/bench.hpp"
#include "overtake/batch/hunt.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/batch/tune.hpp"

namespace overtake::batch {

/// A wall-clock duration as 45s, 3m07s or 2h05m.
[[nodiscard]] std::string duration_text(double s);

/// A bench's bar: runs done, miles simulated, elapsed and the time to go (`total_sim_s`: the
/// simulated seconds of all its runs).
[[nodiscard]] std::string progress_text(const BenchProgress& p, double total_sim_s);
/// A hunt's runs, budget spent, failures and situations found, and the most time to go.
[[nodiscard]] std::string progress_text(const HuntProgress& p);
/// An estimate's runs, budget spent, weighted events, and the rate with its relative width.
[[nodiscard]] std::string progress_text(const RiskProgress& p);
/// A search's trial, the runs of its bench, and the best figure so far.
[[nodiscard]] std::string progress_text(const TuneProgress& p);

}  // namespace overtake::batch
