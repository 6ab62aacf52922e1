#pragma once
// The readers of a design file's sections (one per section, in io/design_*.cpp) and what
// they share: the registry of output file names, the count bounds, actuator lookup, and
// the mapping of the library's own validation back to the file's keys. Private to src/io.
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "freeflex/io/design.hpp"
#include "freeflex/trajopt/problem.hpp"
#include "io/design_reader.hpp"

namespace freeflex::io_detail {

namespace lim = design_limits;

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline const Range kLength = Range::positive().supported(lim::kMinLength_m, lim::kMaxLength_m);
inline const Range kMass = Range::positive().supported(lim::kMinMass_kg, lim::kMaxMass_kg);
inline const Range kMassPerLength =
    Range::positive().supported(lim::kMinMassPerLength_kg_m, lim::kMaxMassPerLength_kg_m);
inline const Range kStiffness = Range::positive().supported(lim::kMinBendingStiffness_Nm2, lim::kMaxBendingStiffness_Nm2);
inline const Range kMassOrZero = Range::nonnegative().supported(-kInf, lim::kMaxMass_kg);
inline const Range kTime = Range::positive().supported(lim::kMinDuration_s, lim::kMaxTime_s);  // durations, horizons
inline const Range kWeight = Range::nonnegative().supported(-kInf, lim::kMaxWeight);
inline const Range kCommand = Range::positive().supported(-kInf, lim::kMaxCommand);  // limits, rate limits

/// Files the studies will write, so that two of them never share a name (one would
/// overwrite the other). A name comes from a design key or is fixed by a study.
class Outputs {
 public:
  /// Files `stem` + each extension, named by `key` of `s` (`given`: in the file, not a default).
  void named(const Section& s, const std::string& key, const std::string& stem, std::vector<std::string> exts) {
    Entry e;
    e.owner = s.key_path(key) + " = \"" + stem + "\"" + (s.has(key) ? "" : " (the default)");
    e.rank = s.has(key) ? 2 : 1;
    e.line = s.line(key);
    for (const auto& x : exts) e.files.push_back(stem + x);
    entries_.push_back(std::move(e));
  }
  /// A file whose name a study fixes.
  void fixed(const std::string& study, const std::string& file) { entries_.push_back({study, {file}, 0, 0}); }

  void check(Problems& problems) const {
    std::vector<const Entry*> order;
    for (const auto& e : entries_) order.push_back(&e);
    // fixed names first, then defaults, then names the file gives in file order: a clash
    // is reported at the key the user can change
    std::stable_sort(order.begin(), order.end(), [](const Entry* a, const Entry* b) {
      return a->rank != b->rank ? a->rank < b->rank : a->line < b->line;
    });
    for (std::size_t i = 0; i < order.size(); ++i) {
      if (order[i]->rank == 0) continue;
      for (std::size_t j = 0; j < i; ++j) {
        std::string shared;
        for (const auto& f : order[i]->files)
          if (std::find(order[j]->files.begin(), order[j]->files.end(), f) != order[j]->files.end())
            shared += (shared.empty() ? "" : ", ") + f;
        if (shared.empty()) continue;
        const Entry& other = *order[j];
        problems.add(order[i]->line, order[i]->owner + " writes " + shared + ", which " + other.owner +
                                         (other.rank == 2 ? " (line " + std::to_string(other.line) + ")" : "") +
                                         " writes too; output files must have distinct names");
        break;
      }
    }
  }

 private:
  struct Entry {
    std::string owner;
    std::vector<std::string> files;
    int rank = 0;  // 0 fixed by a study, 1 a default name, 2 given in the file
    int line = 0;
  };
  std::vector<Entry> entries_;
};

/// Reports at `key` "LEAD with OTHER gives N WHAT; at most LIMIT: ADVICE" when `span`
/// at `step` gives more than `limit` points. LEAD names the reported key and its value
/// ("simulation.output_step_s = 1e-09"), OTHER the other one ("duration_s = 3").
bool check_count(Section& s, const std::string& key, const std::string& lead, const std::string& other, double span,
                 double step, const std::string& what, double limit, const std::string& advice);

/// A count for messages: whole digits while they are exact (below 1e15), else 3e+15.
std::string show_count(double n);

/// `s` without surrounding blanks, in lower case (how Ipopt compares string option values).
std::string lower_trimmed(const std::string& s);
/// `s` without surrounding blanks (how Ipopt reads a value).
std::string trimmed(const std::string& s);

/// Total length of the design's beam (0 while it has no valid segment).
double beam_length(const Design& d);
/// The latest time any load acts (0 without loads).
double loads_end(const Design& d);

/// Resolves [[actuator]] names to element indices (loads come first in force_elements()).
/// Names in `rejected` (actuators with a bad field, already reported) are left out silently.
std::vector<int> actuator_indices(Section& s, const std::string& key, const std::vector<std::string>& names,
                                  const Design& d, const std::vector<std::string>& rejected);

/// A library struct's field and the key of section `s` that sets it.
using FieldKeys = std::vector<std::pair<std::string, std::string>>;
/// Reports the problems the library's own validation found (FieldProblem) at the keys
/// their fields come from, with every field named in the message renamed to its key:
/// "t_min_s = 5 > t_max_s = 2" becomes "maneuver.duration_min_s = 5 > duration_max_s = 2".
/// A problem about a key already reported (a value the reader rejected) is left out, and
/// so is one about a field no key sets (the reader guarantees it).
void report_field_problems(Section& s, const std::vector<FieldProblem>& problems, const FieldKeys& keys);

// One reader per section; each fills its part of the design and reports its problems.
void read_model(Section& root, Design& d);
/// Largest number of shape functions the design's basis offers (kMaxNoa for the paper's).
int max_modes(const Design& d);
void read_beam(Section& root, Design& d);
void read_free_vibration(Section& root, Design& d, Outputs& outputs);
/// Returns the names of the actuators rejected for a bad field (already reported), so that
/// the sections naming them do not report them again as unknown.
std::vector<std::string> read_loads_and_actuators(Section& root, Design& d);
void read_damping(Section& root, Design& d);
/// [motion] (io/design_motion.cpp).
void read_motion(Section& root, Design& d);
void read_simulation(Section& root, Design& d, Outputs& outputs);
void read_maneuver(Section& root, Design& d, Outputs& outputs, const std::vector<std::string>& rejected);
void read_controller(Section& root, Design& d, Outputs& outputs, const std::vector<std::string>& rejected);
/// [[sensor]], [lqg] and [sweep] (io/design_sweep.cpp), after [controller].
void read_sensors_lqg_sweep(Section& root, Design& d, Outputs& outputs);
/// [export] (after [controller], which it needs).
void read_export(Section& root, Design& d, Outputs& outputs);
void read_bang_bang(Section& root, Design& d, Outputs& outputs, const Problems& problems,
                    const std::vector<std::string>& rejected);

}  // namespace freeflex::io_detail
