// Minimum-cost assignment (Hungarian method with row/column potentials, O(n^2 m)).
#pragma once

#include <vector>

namespace beslam::motion {

// cost: rows x cols, row-major, finite. Returns for every row the assigned column or -1 (only when
// rows > cols). Every row (or every column, when there are more rows) is assigned; callers reject
// pairs whose cost is above their gate afterwards.
std::vector<int> solveAssignment(const std::vector<double>& cost, int rows, int cols);

}  // namespace beslam::motion
