#pragma once
// Seeded mutations of design texts, for the fuzz tests (tests/io/test_fuzz.cpp and the
// command-line runs of tests/cli/test_cli_hardening.cpp).
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace freeflex_test {

inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

inline std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

/// One seeded mutation of a design text: values replaced by extremes, lines dropped,
/// repeated or moved, keys misspelt, strings made long or odd, the text cut or sprayed
/// with bytes. Mutations that change a value keep the line's key, so most mutants reach
/// the validation of that key rather than stopping at the TOML parser.
inline std::string mutate(const std::string& text, std::mt19937& rng) {
  static const char* const numbers[] = {"0",   "-1",  "1e308", "-1e-308", "1e-300",       "nan",  "inf",
                                        "-inf", "2147483648", "9223372036854775807", "1.5", "100000",
                                        "1e6", "1e-9", "0.5",  "100",     "101",          "[]",   "\"x\""};
  static const char* const strings[] = {"\"\"", "\"../x\"", "\"a\\tb\"", "\"\\u0001\"", "\"summary\"",
                                        "\"hermite_simpson\"", "\"second-order\"", "1", "true"};
  std::vector<std::string> lines = lines_of(text);
  auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  const int edits = 1 + static_cast<int>(pick(3));
  for (int e = 0; e < edits && !lines.empty(); ++e) {
    std::string& line = lines[pick(lines.size())];
    const auto eq = line.find(" = ");
    switch (pick(9)) {
      case 0:
      case 1:  // a value becomes an extreme number (or another type)
        if (eq != std::string::npos) line = line.substr(0, eq + 3) + numbers[pick(std::size(numbers))];
        break;
      case 2:  // a value becomes an odd string
        if (eq != std::string::npos) line = line.substr(0, eq + 3) + strings[pick(std::size(strings))];
        break;
      case 3:  // a line is dropped
        line.clear();
        break;
      case 4:  // a line is repeated (duplicate keys, repeated tables)
        lines.push_back(line);
        break;
      case 5:  // a key is misspelt
        if (eq != std::string::npos && eq > 1) line.erase(pick(eq), 1);
        break;
      case 6:  // an array grows long
        if (eq != std::string::npos) {
          std::string a = line.substr(0, eq + 3) + "[";
          const std::size_t n = 1 + pick(300);
          for (std::size_t i = 0; i < n; ++i) a += (i ? ", " : "") + std::to_string(1 + pick(120));
          line = a + "]";
        }
        break;
      case 7:  // a table is repeated further down
        lines.insert(lines.begin() + static_cast<long>(pick(lines.size())), line);
        break;
      default: {  // a byte somewhere
        if (!line.empty()) line[pick(line.size())] = static_cast<char>(pick(256));
      }
    }
  }
  std::string out = joined(lines);
  if (pick(20) == 0) out.resize(pick(out.size() + 1));  // cut short
  return out;
}

}  // namespace freeflex_test
