// This process's memory, for run reports: the resident set now (per frame in timing.csv) and its peak
// (summary.json). Linux: /proc/self/statm and getrusage; 0 where the system does not say.
#pragma once

namespace beslam {

// Resident set size now, MiB.
double residentMemoryMb();

// Largest resident set size of this process so far, MiB.
double peakResidentMemoryMb();

}  // namespace beslam
