// The fuzz corpus: the designs that found issue 20's defects (tests/io/fuzz_corpus, each
// with the message it must now get), and a seeded mutation run over the shipped designs:
// whatever a mutant holds, reading it either gives a Design or a DesignError whose every
// line names the file, and a design that loads stays within the bounds it promises.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <vector>

#include "freeflex/io/design.hpp"
#include "support/designs.hpp"
#include "support/files.hpp"
#include "support/mutate.hpp"

using namespace freeflex;
using namespace freeflex_test;
using Catch::Contains;

namespace {

std::vector<std::filesystem::path> files_in(const std::string& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".toml") files.push_back(e.path());
  std::sort(files.begin(), files.end());  // the run must not depend on the directory's order
  return files;
}

/// True if `message` is a DesignError's text: every line names the file.
bool names_the_file(const std::string& message) {
  for (const auto& line : lines_of(message))
    if (line.rfind("design 't.toml'", 0) != 0) return false;
  return !message.empty();
}

}  // namespace

TEST_CASE("the designs that found issue 20's defects get their messages", "[io][fuzz]") {
  const auto files = files_in(std::string(FREEFLEX_SOURCE_DIR) + "/tests/io/fuzz_corpus");
  REQUIRE(files.size() >= 7);
  for (const auto& f : files) {
    const std::string text = read_text(f);
    const auto lines = lines_of(text);
    REQUIRE(lines.size() > 2);
    const std::string tag = "# expect: ";
    REQUIRE(lines[1].rfind(tag, 0) == 0);
    const std::string expected = lines[1].substr(tag.size());
    INFO(f.filename().string());
    if (expected == "ok") CHECK(problems_of(text).empty());
    else CHECK_THAT(problems_of(text), Contains(expected));
  }
}

TEST_CASE("seeded mutants of the shipped designs load or are refused, never anything else", "[io][fuzz]") {
  std::mt19937 rng(20);  // issue 20: the same mutants on every run
  const auto designs = files_in(std::string(FREEFLEX_SOURCE_DIR) + "/designs");
  REQUIRE(designs.size() >= 7);
  int loaded = 0, refused = 0;
  for (int k = 0; k < 400; ++k) {
    const std::string base = read_text(designs[static_cast<std::size_t>(k) % designs.size()]);
    const std::string text = mutate(base, rng);
    INFO("mutant " << k << " of " << designs[static_cast<std::size_t>(k) % designs.size()].filename() << ":\n"
                   << text);
    try {
      const Design d = parse_design(text, "t.toml");
      ++loaded;
      // what loads keeps the bounds the README promises
      CHECK(d.title.size() <= design_limits::kMaxTitleBytes);
      if (d.free_vibration) {
        CHECK(d.free_vibration->noa_sweep.size() <= static_cast<std::size_t>(design_limits::kMaxNoaSweep));
        CHECK(d.free_vibration->mode_shapes.size() <= static_cast<std::size_t>(design_limits::kMaxModeShapes));
        double rows = 0;
        for (const auto& m : d.free_vibration->mode_shapes) rows += m.points;
        CHECK(rows <= design_limits::kMaxModeShapeRows);
      }
      if (d.simulation) {
        const auto& o = d.simulation->options;
        CHECK(o.duration_s / o.output_step_s <= design_limits::kMaxOutputRows);
      }
      if (d.maneuver) CHECK(d.maneuver->options.intervals <= design_limits::kMaxIntervals);
    } catch (const DesignError& e) {
      ++refused;
      CHECK(names_the_file(e.what()));
    }
  }
  // the run exercises both sides (seed 20: 76 of the 400 load, 324 are refused)
  CHECK(loaded > 20);
  CHECK(refused > 200);
}
