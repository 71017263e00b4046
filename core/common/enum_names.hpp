#pragma once
// The names an enum's values carry at the edges (JSON, the database, OpenAPI's `enum` lists, the
// CLI), written once per enum as a table: an enum opts in by specialising EnumNames with a
// constexpr `table` of {value, name} pairs, and every conversion either way reads that table, so a
// new value cannot be named in one place and forgotten in another.
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace rover {

template <class E>
struct EnumName {
  E value;
  std::string_view name;
};

// Specialise with `static constexpr std::array<EnumName<E>, N> table{{...}}` listing every value
// once; the table's order is the order published (OpenAPI, the page).
template <class E>
struct EnumNames;

template <class E>
concept NamedEnum = std::is_enum_v<E> && requires { EnumNames<E>::table; };

// The name of a value; a value missing from its table is a programming error caught by the tests
// that walk every table (tests/core/test_enum_names.cpp), so "unknown" never reaches a client.
template <NamedEnum E>
constexpr std::string_view enumName(E value) {
  for (const auto& entry : EnumNames<E>::table)
    if (entry.value == value) return entry.name;
  return "unknown";
}

// The value a name stands for; nullopt for a name not in the table (the caller decides whether
// that is a 400, a corrupt row or a default).
template <NamedEnum E>
constexpr std::optional<E> parseEnum(std::string_view name) {
  for (const auto& entry : EnumNames<E>::table)
    if (entry.name == name) return entry.value;
  return std::nullopt;
}

// Every name in table order, e.g. for an OpenAPI `enum` list.
template <NamedEnum E>
std::vector<std::string> enumNames() {
  std::vector<std::string> out;
  for (const auto& entry : EnumNames<E>::table) out.emplace_back(entry.name);
  return out;
}

}  // namespace rover
