#pragma once

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
