#pragma once
//! \file The msdeform exception hierarchy. Every message names what is wrong and where (file and line,
//! vertex or face id) and, where there is one, what to do about it.

#include <stdexcept>
#include <string>

namespace msd {

//! Base of all msdeform errors.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

//! The caller's data is unusable: a missing or malformed file, a wrong count, a non-finite number.
class InvalidInput : public Error {
 public:
  using Error::Error;
};

//! The mesh or region has a structure the algorithm cannot handle (e.g. an unconstrained free component).
class TopologyError : public Error {
 public:
  using Error::Error;
};

//! A numerical solve failed (matrix not positive definite, factorisation ran out of memory, ...).
class SolverError : public Error {
 public:
  explicit SolverError(const std::string& what, long index = -1) : Error(what), index_(index) {}
  //! The matrix column (variable) where the failure showed, or -1 when not known.
  long index() const { return index_; }

 private:
  long index_;
};

//! A method was called in the wrong order or with arguments that contradict an earlier call.
class UsageError : public Error {
 public:
  using Error::Error;
};

}  // namespace msd
