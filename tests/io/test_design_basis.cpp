// [model] basis keys (basis, elements, element_order) and tapered [beam] properties
// ([start, end] pairs): loading, defaults, and every problem reported with key and line.
#include <catch2/catch.hpp>

#include <string>

#include "freeflex/io/design.hpp"
#include "support/designs.hpp"

using namespace freeflex;
using namespace freeflex_test;
using Catch::Contains;

namespace {

const std::string kUniform = "[beam]\nlength_m = 1.0\nmass_kg = 1.0\nbending_stiffness_Nm2 = 1.0\n";

}  // namespace

TEST_CASE("the shipped stepped beam loads on the finite-element basis", "[io]") {
  const Design d = load_design(std::string(FREEFLEX_SOURCE_DIR) + "/designs/stepped_beam.toml");
  CHECK(d.basis.kind == BasisOptions::Kind::FiniteElement);
  CHECK(d.basis.finite_element.elements == 40);
  CHECK(d.basis.finite_element.order == 5);
  REQUIRE(d.beam.segments.size() == 2);
  CHECK(d.beam.segments[1].bending_stiffness_Nm2 == 0.8);
  CHECK(d.body().basis().name() == "finite_element");
}

TEST_CASE("[model] basis keys: defaults, values, and the paper's basis when not asked", "[io]") {
  const Design paper = parse_design(kUniform, "t.toml");
  CHECK(paper.basis.kind == BasisOptions::Kind::Paper);
  CHECK(paper.body().basis().name() != "finite_element");
  const Design fe = parse_design(kUniform + "[model]\nbasis = \"finite_element\"\n", "t.toml");
  CHECK(fe.basis.kind == BasisOptions::Kind::FiniteElement);
  CHECK(fe.basis.finite_element.elements == FiniteElementOptions{}.elements);
  CHECK(fe.basis.finite_element.order == FiniteElementOptions{}.order);
  const Design cubic =
      parse_design(kUniform + "[model]\nbasis = \"finite_element\"\nelements = 12\nelement_order = 3\nnoa = 24\n", "t.toml");
  CHECK(cubic.basis.finite_element.elements == 12);
  CHECK(cubic.basis.finite_element.order == 3);
  CHECK(cubic.noa == 24);  // 12 cubic elements: 2 * 13 - 2 = 24 elastic modes
  CHECK(fe.basis.finite_element.modes == FiniteElementOptions::Modes::FreeFree);  // the default
  const Design clamped =
      parse_design(kUniform + "[model]\nbasis = \"finite_element\"\nfe_modes = \"clamped_at_reference\"\n", "t.toml");
  CHECK(clamped.basis.finite_element.modes == FiniteElementOptions::Modes::ClampedAtReference);
  CHECK(clamped.body().basis().name() == "finite_element");
}

TEST_CASE("[model] bad basis keys name key, line, value and what is allowed", "[io]") {
  CHECK_THAT(problems_of(kUniform + "[model]\nbasis = \"fem\"\n"), Contains("line 6: model.basis = \"fem\""));
  CHECK_THAT(problems_of(kUniform + "[model]\nbasis = \"fem\"\n"), Contains("finite_element"));
  CHECK_THAT(problems_of(kUniform + "[model]\nbasis = \"finite_element\"\nelements = 0\n"),
             Contains("line 7: model.elements = 0, must be a whole number in [1, 2000]"));
  CHECK_THAT(problems_of(kUniform + "[model]\nbasis = \"finite_element\"\nelement_order = 4\n"),
             Contains("line 7: model.element_order = 4, must be 3 or 5"));
  CHECK_THAT(problems_of(kUniform + "[model]\nbasis = \"finite_element\"\nfe_modes = \"clamped\"\n"),
             Contains("line 7: model.fe_modes = \"clamped\""));
  CHECK_THAT(problems_of(kUniform + "[model]\nbasis = \"finite_element\"\nfe_modes = \"clamped\"\n"),
             Contains("clamped_at_reference"));
  CHECK_THAT(problems_of(kUniform + "[model]\nfe_modes = \"free_free\"\n"),
             Contains("line 6: model.fe_modes applies to basis = \"finite_element\" only"));
  CHECK_THAT(problems_of(kUniform + "[model]\nelements = 10\n"),
             Contains("line 6: model.elements applies to basis = \"finite_element\" only"));
  CHECK_THAT(problems_of(kUniform + "[model]\nbasis = \"finite_element\"\nelements = 2\nelement_order = 3\nnoa = 5\n"),
             Contains("model.noa = 5, but 2 cubic elements have 4 elastic modes"));
  // the default noa (6) against too few elements is reported at elements
  CHECK_THAT(problems_of(kUniform + "[model]\nbasis = \"finite_element\"\nelements = 1\nelement_order = 3\n"),
             Contains("line 7: model.noa = 6 (the default), but 1 cubic elements have 2 elastic modes"));
  // every problem at once
  const std::string all =
      problems_of(kUniform + "[model]\nbasis = \"finite_element\"\nelements = -3\nelement_order = 7\nnoa = 0\n");
  CHECK_THAT(all, Contains("model.elements = -3"));
  CHECK_THAT(all, Contains("model.element_order = 7"));
  CHECK_THAT(all, Contains("model.noa = 0"));
}

TEST_CASE("tapered beam and segments: [start, end] pairs load, bad pairs are reported", "[io]") {
  const Design d = parse_design(
      "[beam]\nlength_m = 2.0\nmass_per_length_kg_m = [1.2, 0.4]\nbending_stiffness_Nm2 = [2.0, 0.5]\n", "t.toml");
  REQUIRE(d.beam.segments.size() == 1);
  const BeamSegment& s = d.beam.segments[0];
  CHECK(s.tapered());
  CHECK(s.mass_per_length_kg_m == 1.2);
  CHECK(s.mass_per_length_end() == 0.4);
  CHECK(s.bending_stiffness_end() == 0.5);
  CHECK(Beam(d.beam).distributed_mass() == Approx(1.6).epsilon(1e-15));  // (1.2 + 0.4) / 2 * 2 m, to round-off
  const Design seg = parse_design(
      "[[beam.segment]]\nlength_m = 0.5\nmass_per_length_kg_m = 1.0\nbending_stiffness_Nm2 = [1.0, 2.0]\n"
      "[[beam.segment]]\nlength_m = 0.5\nmass_per_length_kg_m = 1.0\nbending_stiffness_Nm2 = 2.0\n",
      "t.toml");
  CHECK(seg.beam.segments[0].tapered());
  CHECK(!seg.beam.segments[1].tapered());
  CHECK_THAT(problems_of("[beam]\nlength_m = 1.0\nmass_per_length_kg_m = [1.0, 0.5, 0.2]\nbending_stiffness_Nm2 = 1.0\n"),
             Contains("line 3: beam.mass_per_length_kg_m has 3 entries, must be a number or [start, end]"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1.0\nmass_per_length_kg_m = 1.0\nbending_stiffness_Nm2 = [1.0, -0.5]\n"),
             Contains("beam.bending_stiffness_Nm2"));
  CHECK_THAT(problems_of("[beam]\nlength_m = 1.0\nmass_per_length_kg_m = 1.0\nbending_stiffness_Nm2 = [1.0, -0.5]\n"),
             Contains("-0.5"));
}
