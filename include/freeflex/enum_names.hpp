#pragma once
// Names of the public enums: one spelling per value, the one design files use, shared by
// summary.json, messages and (later) the Python module. Each enum that crosses a file or
// a summary specializes EnumNames beside its declaration:
//
//   template <> struct EnumNames<Transcription> {
//     static constexpr const char* what = "transcription";
//     static constexpr std::array<std::pair<Transcription, const char*>, 3> names{{...}};
//   };
//
// and gets to_string / from_string / enum_names from the templates below.
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace freeflex {

/// Specialized for every named enum (see above); the primary template names nothing.
template <class E>
struct EnumNames {};

namespace detail {
template <class E, class = void>
struct has_names : std::false_type {};
template <class E>
struct has_names<E, std::void_t<decltype(EnumNames<E>::names)>> : std::true_type {};
}  // namespace detail

/// The name of `value` ("hermite_simpson"); "?" for a value outside the enum.
template <class E, std::enable_if_t<detail::has_names<E>::value, int> = 0>
const char* to_string(E value) {
  for (const auto& [v, name] : EnumNames<E>::names)
    if (v == value) return name;
  return "?";
}

/// The value named `name`, or nothing if no value has that name (names are exact: lower
/// case, words joined by '_').
template <class E, std::enable_if_t<detail::has_names<E>::value, int> = 0>
std::optional<E> parse_enum(std::string_view name) {
  for (const auto& [v, n] : EnumNames<E>::names)
    if (name == n) return v;
  return std::nullopt;
}

/// Every name, in declaration order.
template <class E, std::enable_if_t<detail::has_names<E>::value, int> = 0>
std::vector<std::string> enum_names() {
  std::vector<std::string> out;
  for (const auto& item : EnumNames<E>::names) out.emplace_back(item.second);
  return out;
}

/// The value named `name`. Throws std::invalid_argument naming the enum, the name and
/// the allowed names: "unknown transcription 'rk4', expected one of 'trapezoidal', ...".
template <class E, std::enable_if_t<detail::has_names<E>::value, int> = 0>
E from_string(std::string_view name) {
  if (const auto v = parse_enum<E>(name)) return *v;
  std::string allowed;
  for (const auto& n : enum_names<E>()) allowed += (allowed.empty() ? "'" : ", '") + n + "'";
  throw std::invalid_argument("unknown " + std::string(EnumNames<E>::what) + " '" + std::string(name) +
                              "', expected one of " + allowed);
}

}  // namespace freeflex
