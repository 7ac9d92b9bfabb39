// Order pointers by their object's id: containers iterate in creation order, never in address order,
// so runs are deterministic.
#pragma once

namespace beslam::orb {

template <class T>
struct IdLess {
  bool operator()(const T* a, const T* b) const { return a->id < b->id; }
};

}  // namespace beslam::orb
