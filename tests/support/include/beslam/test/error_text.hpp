// errorText: the message of the exception a call throws, for tests that check what an error says.
#pragma once

#include <exception>
#include <string>

namespace beslam::test {

// The message of the exception of type E that f() throws, or "" when it throws none (any other type
// escapes to the test).
template <class E, class F>
std::string errorText(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

}  // namespace beslam::test
