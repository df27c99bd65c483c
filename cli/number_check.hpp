// The check of a number option, in sidc's words: CLI11's own range checks print the whole range of
// a double and take "inf". The whole text must read as a number (std::from_chars: no locale, no
// leading blanks) for which `holds` is true; anything else gets `message`, where `{}` stands for
// the text given.
#pragma once

#include <charconv>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

namespace sidc {

inline CLI::Validator number_check(const std::string& name, bool (*holds)(double), const std::string& message) {
  return CLI::Validator(
      [holds, message](std::string& text) -> std::string {
        double v = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec == std::errc() && end == text.data() + text.size() && holds(v)) return {};
        return fmt::format(fmt::runtime(message), text);
      },
      name);
}

// A whole-number option of at least `least`: "-1" for a count is refused (CLI11 reads it into an
// unsigned type as 2^64 - 1), and so are "2.5", "1e3" and "inf", each with sidc's message.
inline CLI::Validator whole_number_check(long long least) {
  return CLI::Validator(
      [least](std::string& text) -> std::string {
        long long v = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec == std::errc() && end == text.data() + text.size() && v >= least) return {};
        return least == 0 ? fmt::format("`{}` is not a whole number of 0 or more", text)
                          : fmt::format("`{}` is not a whole number of {} or more", text, least);
      },
      least == 0 ? "NONNEGATIVE" : least == 1 ? "POSITIVE" : fmt::format("AT LEAST {}", least));
}

}  // namespace sidc
