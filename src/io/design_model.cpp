// [model]: the number of shape functions and the basis they come from (the paper's
// admissible functions, or finite-element modes with their element count and order, and
// which modes: free-free or clamped at o), and whether the model keeps geometric stiffening.
#include <algorithm>

#include "freeflex/model/basis.hpp"
#include "freeflex/model/modal_integrals.hpp"
#include "io/design_sections.hpp"

namespace freeflex::io_detail {

int max_modes(const Design& d) {
  if (d.basis.kind != BasisOptions::Kind::FiniteElement) return kMaxNoa;
  // elastic modes of the element model: (w, w') per node, two bubbles per quintic element,
  // less the two rigid modes (more elements when the beam's key points ask for them)
  const FiniteElementOptions& fe = d.basis.finite_element;
  return std::min(kMaxNoa, (fe.order == 5 ? 4 : 2) * fe.elements);
}

void read_model(Section& root, Design& d) {
  Section model = root.table("model");
  auto noa = model.integer("noa", 1, kMaxNoa, false);
  if (auto kind = model.enumerated<BasisOptions::Kind>("basis", false)) d.basis.kind = *kind;
  const bool fe = d.basis.kind == BasisOptions::Kind::FiniteElement;
  FiniteElementOptions& o = d.basis.finite_element;
  if (auto n = model.integer("elements", 1, kMaxElements, false)) o.elements = static_cast<int>(*n);
  if (auto p = model.integer("element_order", 3, 5, false)) {
    if (*p == 4) model.problem("element_order", model.key_path("element_order") + " = 4, must be 3 or 5");
    else o.order = static_cast<int>(*p);
  }
  if (auto m = model.enumerated<FiniteElementOptions::Modes>("fe_modes", false)) o.modes = *m;
  for (const char* key : {"elements", "element_order", "fe_modes"})
    if (!fe && model.has(key) && !model.has_problem(key))
      model.problem(key, model.key_path(key) + " applies to basis = \"finite_element\" only (the basis is \"" +
                             to_string(d.basis.kind) + "\")");
  const int n = static_cast<int>(noa.value_or(d.noa));
  if (fe && n > max_modes(d) && !model.has_problem("elements")) {
    const std::string key = noa ? "noa" : "elements";
    model.problem(key, model.key_path("noa") + " = " + std::to_string(n) + (noa ? "" : " (the default)") +
                           ", but " + std::to_string(o.elements) + (o.order == 5 ? " quintic" : " cubic") +
                           " elements have " + std::to_string(max_modes(d)) +
                           " elastic modes; ask for at most that many, or for more elements");
  } else {
    d.noa = n;
  }
  d.geometric_stiffening = model.boolean("geometric_stiffening", false).value_or(d.geometric_stiffening);
  model.finish();
}

}  // namespace freeflex::io_detail
