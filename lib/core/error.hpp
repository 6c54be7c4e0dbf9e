// Errors. Every user-facing error names what went wrong and where (file, key, line, particle).
#pragma once

#include <stdexcept>
#include <string>

namespace sphdem {

// Bad input: a scene file, a key, a value. The message is shown to the user as is.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A run that went unstable (DESIGN.md §7). The message says which guard fired and why.
class StabilityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An internal invariant broken (a bug, or a resource that failed).
class RuntimeFault : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace sphdem
