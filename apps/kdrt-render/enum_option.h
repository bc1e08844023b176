// Options that take one of an enum's names: CLI11 checks the value and the
// help lists the choices, both from the library's table (<kdrt/enum_names.h>).
#pragma once

#include <kdrt/enum_names.h>

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace kdrt::cli {

// "a (what a is) | b (what b is)", after `lead`.
template <class E>
std::string enum_help(std::string lead = "") {
    const char* separator = "";
    for (const EnumName<E>& n : enum_names<E>()) {
        lead += separator + std::string(n.name) + " (" + n.description + ")";
        separator = " | ";
    }
    return lead;
}

// Rejects a value that is none of E's names ("--flag: x not in {a,b}").
template <class E>
CLI::IsMember is_enum_name() {
    std::vector<std::string> names;
    for (const EnumName<E>& n : enum_names<E>()) names.emplace_back(n.name);
    return CLI::IsMember(names);
}

}  // namespace kdrt::cli
