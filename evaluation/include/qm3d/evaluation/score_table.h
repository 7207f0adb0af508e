// CSV tables of scores, features and subjective scores for `qm3d eval` and `qm3d train`: reading
// with a header row, finding columns, parsing numbers, and joining two tables on a stimulus key
// so that every row without a partner is counted and named, never silently dropped.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace qm3d::evaluation {

/// How many keys of a list of unmatched or skipped rows are shown (stderr and JSON).
inline constexpr std::size_t kKeysShown = 5;

/// A CSV file with a header row (RFC 4180 fields, one record per line, blank lines ignored).
struct CsvTable {
  std::string path;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;  ///< each with header.size() fields
  std::vector<std::size_t> line_numbers;       ///< 1-based line of each row
};

/// Reads a table. @throws InputError (unreadable), FormatError naming the file and line (no
/// header, a row with a different number of fields, a repeated column name).
CsvTable read_csv_table(const std::filesystem::path& path);

/// Index of the column `name`, or nullopt.
std::optional<std::size_t> find_column(const CsvTable& table, const std::string& name);

/// Index of the column `name`. @throws FormatError "FILE: no column "x" (columns: ...); set
/// with OPTION".
std::size_t require_column(const CsvTable& table, const std::string& name,
                           const std::string& option);

/// The key column: `name` when given, else "distorted" when the table has it (the results of
/// `qm3d batch`), else the first column.
std::size_t key_column(const CsvTable& table, const std::string& name, const std::string& option);

/// The value column: `name` when given, else the first of `preferred` present (compared without
/// case), else the column other than `key` of a two-column table.
/// @throws FormatError  naming the file, its columns and `option`, when none applies
std::size_t value_column(const CsvTable& table, const std::string& name,
                         const std::vector<std::string>& preferred, std::size_t key,
                         const std::string& option);

/// The number in a cell; nullopt when the cell is empty or "nan"/"NA" (a missing value).
/// @throws FormatError "FILE:LINE: column "x": "abc" is not a number".
/// `allow_infinite`: "inf" / "-inf" (a PSNR of identical inputs) are values, not errors.
std::optional<double> cell_number(const CsvTable& table, std::size_t row, std::size_t column,
                                  bool allow_infinite = false);

/// A list of keys, counted, with the first few kept for messages.
struct KeyList {
  std::size_t count = 0;
  std::vector<std::string> first;  ///< at most kKeysShown
  void add(const std::string& key);
  std::string examples() const;  ///< "a, b, c" or "a, b, c, d, e, ..." (more than shown)
};

/// A key's file stem ("/data/p01_r1.ply" -> "p01_r1"), as --stem compares keys.
std::string stem_of(const std::string& key);

/// The rows of two tables that share a key.
struct JoinedRows {
  std::vector<std::string> keys;         ///< in the order of the left table
  std::vector<std::size_t> left, right;  ///< row indices
  KeyList left_only, right_only;         ///< keys without a partner
};

/// Joins on the key columns. With `by_stem`, a key is compared by its file stem (directories
/// and last extension removed: "/data/p01_r1.ply" -> "p01_r1").
/// @throws FormatError  a key repeated within one table (naming both lines), or an empty key
JoinedRows join_on_key(const CsvTable& left, std::size_t left_key, const CsvTable& right,
                       std::size_t right_key, bool by_stem);

}  // namespace qm3d::evaluation
