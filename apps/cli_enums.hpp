// Options whose values are the library's enums, named on the command line as to_string() names
// them, so that the parser, the help and the reports agree.
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <string>
#include <vector>

#include "penumbra/flatland/render.hpp"

// `value` must outlive the parse; the help lists the names in the order given.
template <class E>
CLI::Option* add_enum_option(CLI::App* app, const std::string& name, E& value,
                             const std::vector<E>& values, const std::string& help) {
  std::vector<std::string> list;
  std::map<std::string, E> names;
  for (E v : values) {
    list.push_back(penumbra::flatland::to_string(v));
    names[list.back()] = v;
  }
  return app
      ->add_option_function<std::string>(
          name, [&value, names](const std::string& s) { value = names.at(s); }, help)
      ->check(CLI::IsMember(list))
      ->default_str(penumbra::flatland::to_string(value));
}
