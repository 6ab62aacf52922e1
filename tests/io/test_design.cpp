// Design files: whole-file validation, messages naming key and line, unknown keys.
#include <catch2/catch.hpp>

#include "freeflex/io/design.hpp"

using namespace freeflex;
using Catch::Contains;

namespace {
const char* kGood = R"(title = "ok"
[beam]
length_m = 2.0
mass_kg = 3.0
bending_stiffness_Nm2 = 5.0
[model]
noa = 8
)";

std::string problems_of(const std::string& text) {
  try {
    parse_design(text, "t.toml");
  } catch (const DesignError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("a good design loads with units and defaults", "[io]") {
  const Design d = parse_design(kGood, "t.toml");
  REQUIRE(d.beam.segments.size() == 1);
  CHECK(d.beam.segments[0].length_m == 2.0);
  CHECK(d.beam.segments[0].mass_per_length_kg_m == 1.5);
  CHECK(d.noa == 8);
  CHECK(d.plots);
  CHECK(!d.free_vibration);
}

TEST_CASE("the paper's design file loads", "[io]") {
  const Design d = load_design(std::string(FREEFLEX_SOURCE_DIR) + "/designs/paper_table1.toml");
  REQUIRE(d.free_vibration);
  CHECK(d.free_vibration->noa_sweep == std::vector<int>{2, 4, 6, 8, 10});
  REQUIRE(d.free_vibration->mode_shapes.size() == 1);
  CHECK(d.free_vibration->mode_shapes[0].mode == 4);
}

TEST_CASE("bad values name key, line, value and allowed range", "[io]") {
  CHECK_THAT(problems_of("[beam]\nlength_m = -1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n"),
             Contains("design 't.toml' line 2: beam.length_m = -1, must be > 0"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 0\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n"),
             Contains("line 2: beam.length_m = 0, must be > 0"));
  CHECK_THAT(problems_of("[beam]\nlength_m = \"one\"\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n"),
             Contains("line 2: beam.length_m = \"one\", must be a number"));
  CHECK_THAT(problems_of("[beam]\nlength_m = nan\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n"),
             Contains("line 2: beam.length_m = nan, must be a finite number"));
  CHECK_THAT(problems_of(std::string(kGood) + "noa_typo = 3\n"),
             Contains("line 8: unknown key 'model.noa_typo' (allowed here: noa)"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[model]\nnoa = 0\n"),
             Contains("line 6: model.noa = 0, must be a whole number in [1, 100]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[model]\nnoa = 101\n"),
             Contains("model.noa = 101, must be a whole number in [1, 100]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[beam.hub]\nmass_kg = -2\n"),
             Contains("line 6: beam.hub.mass_kg = -2, must be >= 0"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\n[[beam.point_mass]]\n"
                         "position_m = 1.5\nmass_kg = 0.1\n"),
             Contains("line 6: beam.point_mass[1].position_m = 1.5, must be in [0, 1]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1\nmass_kg = 1\nbending_stiffness_Nm2 = 1\nreference_m = 1.0\n"),
             Contains("line 5: beam.reference_m = 1.0, must be in (0, 1)"));
}

TEST_CASE("every problem is reported at once", "[io]") {
  try {
    parse_design("colour = 3\n[beam]\nlength_m = -1\nmass_kg = \"x\"\n[model]\nnoa = 1.5\n", "t.toml");
    FAIL("expected a DesignError");
  } catch (const DesignError& e) {
    const std::string all = e.what();
    CHECK(e.problems().size() == 5);
    CHECK_THAT(all, Contains("line 1: unknown key 'colour'"));
    CHECK_THAT(all, Contains("line 3: beam.length_m = -1"));
    CHECK_THAT(all, Contains("line 4: beam.mass_kg = \"x\", must be a number"));
    CHECK_THAT(all, Contains("line 2: beam.bending_stiffness_Nm2 is required"));
    CHECK_THAT(all, Contains("line 6: model.noa = 1.5, must be a whole number"));
  }
}

TEST_CASE("syntax errors and missing files", "[io]") {
  CHECK_THAT(problems_of("[beam\nlength_m = 1\n"), Contains("design 't.toml' line 1: not valid TOML"));
  CHECK_THROWS_WITH(load_design("/nonexistent/x.toml"),
                    Contains("design '/nonexistent/x.toml': cannot open the file"));
  CHECK_THAT(problems_of("title = \"no beam\"\n"), Contains("section [beam] is required"));
}
