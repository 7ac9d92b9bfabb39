#include "beslam/motion/hungarian.hpp"

#include <limits>
#include <stdexcept>

namespace beslam::motion {

namespace {

// rows <= cols. Shortest augmenting paths with dual potentials u (rows) and v (cols); 1-based arrays
// with column 0 as the virtual start of each augmentation.
std::vector<int> solveWide(const std::vector<double>& a, int n, int m, bool transposed) {
  const double inf = std::numeric_limits<double>::infinity();
  auto at = [&](int i, int j) {
    return transposed ? a[static_cast<size_t>(j) * n + i] : a[static_cast<size_t>(i) * m + j];
  };
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0), minv(m + 1);
  std::vector<int> owner(m + 1, 0), prev(m + 1, 0);
  std::vector<char> done(m + 1);
  for (int i = 1; i <= n; ++i) {
    owner[0] = i;
    int col = 0;
    std::fill(minv.begin(), minv.end(), inf);
    std::fill(done.begin(), done.end(), 0);
    do {
      done[col] = 1;
      const int row = owner[col];
      double delta = inf;
      int next = 0;
      for (int j = 1; j <= m; ++j) {
        if (done[j]) continue;
        const double reduced = at(row - 1, j - 1) - u[row] - v[j];
        if (reduced < minv[j]) minv[j] = reduced, prev[j] = col;
        if (minv[j] < delta) delta = minv[j], next = j;
      }
      for (int j = 0; j <= m; ++j) {
        if (done[j]) {
          u[owner[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      col = next;
    } while (owner[col] != 0);
    do {  // flip the augmenting path
      const int back = prev[col];
      owner[col] = owner[back];
      col = back;
    } while (col != 0);
  }
  std::vector<int> row_to_col(n, -1);
  for (int j = 1; j <= m; ++j)
    if (owner[j] != 0) row_to_col[owner[j] - 1] = j - 1;
  return row_to_col;
}

}  // namespace

std::vector<int> solveAssignment(const std::vector<double>& cost, int rows, int cols) {
  if (rows < 0 || cols < 0 || cost.size() != static_cast<size_t>(rows) * static_cast<size_t>(cols))
    throw std::invalid_argument("solveAssignment: cost matrix size does not match rows x cols");
  if (rows == 0) return {};
  if (cols == 0) return std::vector<int>(rows, -1);
  for (double c : cost)
    if (!(c == c) || c == std::numeric_limits<double>::infinity() || c == -std::numeric_limits<double>::infinity())
      throw std::invalid_argument("solveAssignment: costs must be finite");
  if (rows <= cols) return solveWide(cost, rows, cols, false);
  // More rows than columns: solve the transpose and invert the assignment.
  const std::vector<int> col_to_row = solveWide(cost, cols, rows, true);
  std::vector<int> row_to_col(rows, -1);
  for (int c = 0; c < cols; ++c)
    if (col_to_row[c] >= 0) row_to_col[col_to_row[c]] = c;
  return row_to_col;
}

}  // namespace beslam::motion
