#include "help_format.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <sstream>

namespace qm3d::app {
namespace {

/// The width when neither $COLUMNS nor a terminal says: the classic terminal.
constexpr std::size_t kDefaultHelpWidth = 80;
/// Narrower than this, two columns no longer fit.
constexpr std::size_t kMinHelpWidth = 40;
/// The widest option column (CLI11's default); a narrower terminal gets a third of its width.
constexpr std::size_t kOptionColumn = 30;

class WrappingFormatter : public CLI::Formatter {
 public:
  explicit WrappingFormatter(std::size_t width) : width_(width) {
    column_width(std::min(kOptionColumn, width / 3));
  }

  std::string make_option(const CLI::Option* opt, bool positional) const override {
    return two_columns(make_option_name(opt, positional) + make_option_opts(opt),
                       make_option_desc(opt));
  }

  std::string make_subcommand(const CLI::App* sub) const override {
    return two_columns(sub->get_display_name(), sub->get_description());
  }

  std::string make_description(const CLI::App* app) const override {
    return wrap_lines(CLI::Formatter::make_description(app));
  }

  std::string make_footer(const CLI::App* app) const override {
    return wrap_lines(CLI::Formatter::make_footer(app));
  }

  std::string make_usage(const CLI::App* app, std::string name) const override {
    return wrap_lines(CLI::Formatter::make_usage(app, std::move(name)));
  }

 private:
  // "  NAME" padded to the description column, then the description wrapped in the rest; a
  // name too long for its column is a line (or lines) of its own.
  std::string two_columns(const std::string& name, const std::string& description) const {
    const std::size_t column = get_column_width();
    std::string out = wrap_words("  " + name, width_, 4);
    if (description.empty()) return out + "\n";
    const std::size_t last_line = out.rfind('\n') == std::string::npos ? 0 : out.rfind('\n') + 1;
    if (out.size() - last_line + 1 > column) {
      out += "\n" + std::string(column, ' ');
    } else {
      out += std::string(column - (out.size() - last_line), ' ');
    }
    std::string text = description;
    std::replace(text.begin(), text.end(), '\n', ' ');
    // The first line starts at the column already: wrap as if it were indented.
    const std::string wrapped = wrap_words(std::string(column, ' ') + text, width_, column);
    return out + wrapped.substr(column) + "\n";
  }

  // Every line of `text` wrapped, its continuation lines indented as the line.
  std::string wrap_lines(const std::string& text) const {
    std::istringstream in(text);
    std::string line, out;
    while (std::getline(in, line)) {
      const std::size_t indent = std::min(line.find_first_not_of(' '), line.size());
      out += wrap_words(line, width_, indent) + "\n";
    }
    if (!text.empty() && text.back() != '\n' && !out.empty()) out.pop_back();
    return out;
  }

  std::size_t width_;
};

}  // namespace

std::size_t help_width() {
  std::size_t width = kDefaultHelpWidth;
  if (const char* columns = std::getenv("COLUMNS")) {
    char* end = nullptr;
    const long c = std::strtol(columns, &end, 10);
    if (end != columns && *end == '\0' && c > 0) width = static_cast<std::size_t>(c);
  } else if (::isatty(STDOUT_FILENO)) {
    struct winsize w {};
    if (::ioctl(STDOUT_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col > 0) width = w.ws_col;
  }
  return std::max(width, kMinHelpWidth);
}

std::string wrap_words(const std::string& text, std::size_t width, std::size_t indent) {
  const std::size_t lead = std::min(text.find_first_not_of(' '), text.size());
  std::string out = text.substr(0, lead);
  std::size_t line_start = 0;
  std::istringstream words(text.substr(lead));
  std::string word;
  bool first = true;
  while (words >> word) {
    const std::size_t length = out.size() - line_start;
    if (!first && length + 1 + word.size() > width) {
      out += "\n";
      line_start = out.size();
      out += std::string(indent, ' ') + word;
    } else {
      out += (first ? "" : " ") + word;
    }
    first = false;
  }
  return out;
}

std::shared_ptr<CLI::Formatter> wrapping_formatter(std::size_t width) {
  return std::make_shared<WrappingFormatter>(width);
}

}  // namespace qm3d::app
