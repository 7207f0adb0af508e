// A C locale whose decimal point is ',' (de_DE.UTF-8), as Python's
// locale.setlocale(LC_ALL, "de_DE.UTF-8") sets it, for the tests that number parsing and
// formatting do not depend on the locale. When de_DE.UTF-8 is not installed it is built into a
// temporary folder with localedef (Debian package `locales`) and found through LOCPATH.
#pragma once

#include <clocale>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

namespace qm3d::test {

/// Sets LC_ALL to de_DE.UTF-8 for its lifetime (restoring "C" and LOCPATH after).
class CommaLocale {
 public:
  /// `dir`: where to build the locale if needed.
  explicit CommaLocale(const std::filesystem::path& dir) {
    if (set()) return;
    const bool sources = std::filesystem::exists("/usr/share/i18n/locales/de_DE");
    if (!sources || std::system("command -v localedef > /dev/null 2>&1") != 0) {
      skip_reason_ =
          "de_DE.UTF-8 is not installed and cannot be built (needs localedef and "
          "/usr/share/i18n/locales from the Debian package 'locales')";
      return;
    }
    const std::string cmd =
        "localedef -i de_DE -f UTF-8 '" + (dir / "de_DE.UTF-8").string() + "' > /dev/null 2>&1";
    build_status_ = std::system(cmd.c_str());
    ::setenv("LOCPATH", dir.string().c_str(), 1);
    set_locpath_ = true;
    set();
  }
  ~CommaLocale() {
    std::setlocale(LC_ALL, "C");
    if (set_locpath_) ::unsetenv("LOCPATH");
  }
  CommaLocale(const CommaLocale&) = delete;
  CommaLocale& operator=(const CommaLocale&) = delete;

  /// True when the C locale's decimal point is ',' now.
  bool active() const { return active_; }
  /// Why the locale cannot be had on this machine (then the test may skip); empty when it could
  /// be built, so that a failure to set it is a test failure, never a silent skip.
  const std::string& skip_reason() const { return skip_reason_; }
  int build_status() const { return build_status_; }

 private:
  bool set() {
    active_ = std::setlocale(LC_ALL, "de_DE.UTF-8") != nullptr &&
              std::string(std::localeconv()->decimal_point) == ",";
    return active_;
  }

  bool active_ = false;
  bool set_locpath_ = false;
  int build_status_ = 0;
  std::string skip_reason_;
};

}  // namespace qm3d::test

/// In a test: sets the comma locale for the rest of the scope, skipping with the reason only
/// when the machine cannot provide it (GTEST_SKIP), failing when it could but did not.
#define QM3D_WITH_COMMA_LOCALE(guard, dir)                                                  \
  ::qm3d::test::CommaLocale guard(dir);                                                     \
  if (!guard.active() && !guard.skip_reason().empty()) GTEST_SKIP() << guard.skip_reason(); \
  ASSERT_TRUE(guard.active()) << "de_DE.UTF-8 could not be set (localedef status "          \
                              << guard.build_status() << ")"
