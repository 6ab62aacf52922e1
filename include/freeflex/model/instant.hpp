#pragma once
// The instant at which every time-dependent quantity is evaluated: a time and the piece
// of the timeline it belongs to.
//
// One convention for the whole library (docs/api.md): public functions return their
// results by value, or in a Data workspace the caller owns (made by create_data());
// none writes through an output parameter. The exception are callbacks that the library
// calls, such as an ODE right-hand side or a command function: like CVODES, the library
// hands them a buffer of the right size and they write their result into it.

namespace freeflex {

/// A time together with the piece of the timeline it belongs to. Loads jump at
/// breakpoints; they are evaluated with the formula of the piece that contains
/// `piece_mid`, so an evaluation exactly at a piece's end uses that piece's limit.
struct Instant {
  double t;
  double piece_mid;
  static Instant at(double t) { return {t, t}; }
};

}  // namespace freeflex
