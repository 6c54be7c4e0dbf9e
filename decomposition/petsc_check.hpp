// Internal to decomposition/: turns a failed PETSc call into a sphdem::RuntimeFault. PETSc's own
// error handler has already printed its traceback by then; the exception names the call.
#pragma once

#include <petscsys.h>

#include <string>

#include "core/error.hpp"

namespace sphdem {
namespace detail {

[[noreturn]] inline void throw_petsc_error(PetscErrorCode code, const char* call, const char* file,
                                           int line) {
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  throw RuntimeFault(std::string("PETSc call failed (") + (text ? text : "unknown error") +
                     "): " + call + " at " + file + ":" + std::to_string(line));
}

}  // namespace detail
}  // namespace sphdem

#define SPHDEM_PETSC(call)                                                                \
  do {                                                                                    \
    const PetscErrorCode sphdem_petsc_ierr_ = (call);                                     \
    if (sphdem_petsc_ierr_ != 0)                                                          \
      ::sphdem::detail::throw_petsc_error(sphdem_petsc_ierr_, #call, __FILE__, __LINE__); \
  } while (0)
