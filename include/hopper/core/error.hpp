#pragma once
// Exceptions with context. Each layer throws its own kind so that callers can tell a bad input
// (ConfigError, StoreError) from a numerical failure (SimulationError).

#include <stdexcept>
#include <string>

namespace hopper::core {

class Error : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// A sweep file, command line or parameter set that is not allowed.
class ConfigError : public Error {
  public:
    using Error::Error;
};

// A simulation that cannot go on (non-finite state, overlap blow-up, ...).
class SimulationError : public Error {
  public:
    using Error::Error;
};

// A store that cannot be read or written.
class StoreError : public Error {
  public:
    using Error::Error;
};

// Bytes that cannot be decoded: truncated, damaged, or not what they claim to be
// (core::ByteReader; a layer may report the same failure as its own kind, see bytes.hpp).
class DecodeError : public Error {
  public:
    using Error::Error;
};

}  // namespace hopper::core
