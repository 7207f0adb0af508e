// `--help` text wrapped to the terminal: a CLI11 formatter whose option and command
// descriptions wrap at word boundaries into the description column.
#pragma once

#include <CLI/CLI.hpp>
#include <cstddef>
#include <memory>
#include <string>

namespace qm3d::app {

/// The width help text is wrapped to: $COLUMNS when it is a number, else the terminal's width
/// when stdout is one, else kDefaultHelpWidth; never below kMinHelpWidth.
std::size_t help_width();

/// Words of `text` on lines of at most `width` characters, each but the first starting with
/// `indent` spaces (a word longer than a line stands alone on its line).
std::string wrap_words(const std::string& text, std::size_t width, std::size_t indent);

/// The formatter of every command: two columns (option and default | description), the
/// description wrapped within `width`.
std::shared_ptr<CLI::Formatter> wrapping_formatter(std::size_t width);

}  // namespace qm3d::app
