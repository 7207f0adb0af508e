// Scoring one list on several machines: `qm3d batch --shard K/N` scores one of N deterministic,
// size-balanced parts of the list's pairs, and `qm3d merge` joins the parts' results into the
// rows a single `qm3d batch` would have written. Pure functions (apart from input_bytes).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace qm3d::study {

/// Part `index` (0-based) of `count` parts.
struct Shard {
  std::size_t index = 0;
  std::size_t count = 1;
};

/// Parses "K/N" (0 <= K < N, N >= 1; digits only). Throws std::invalid_argument with a one-line
/// message quoting `text` and saying what is wrong.
Shard parse_shard(const std::string& text);

/// Splits rows of the given sizes into `count` parts, balanced by total size (greedy
/// longest-processing-time: rows by size, largest first, ties by row index, each going to the
/// part with the smallest total so far, ties to the lowest part index). Every row is in exactly
/// one part; each part's row indices are ascending. Depends only on `sizes` and `count`.
std::vector<std::vector<std::size_t>> partition_by_size(const std::vector<std::uintmax_t>& sizes,
                                                        std::size_t count);

/// The rows of part `shard.index` of partition_by_size(sizes, shard.count).
std::vector<std::size_t> shard_rows(const std::vector<std::uintmax_t>& sizes, Shard shard);

/// The size of a file in bytes; 0 when it does not exist or is not a regular file (such a pair
/// still lands in one shard, where scoring it records its error).
std::uintmax_t input_bytes(const std::filesystem::path& path) noexcept;

/// The elements of `rows` in part `shard`, in their order; `size_of(row)` is the row's weight.
template <class T, class SizeOf>
std::vector<T> select_shard(const std::vector<T>& rows, Shard shard, SizeOf size_of) {
  std::vector<std::uintmax_t> sizes;
  sizes.reserve(rows.size());
  for (const T& row : rows) sizes.push_back(size_of(row));
  std::vector<T> selected;
  for (const std::size_t i : shard_rows(sizes, shard)) selected.push_back(rows[i]);
  return selected;
}

/// One row of a batch list, as written there (metric "auto" when the column is absent or empty).
struct ListPair {
  std::string reference, distorted, metric;
  /// Texture maps replacing the meshes' own (header columns ref_texture, dist_texture: as
  /// --ref-texture / --dist-texture); empty = none.
  std::string ref_texture, dist_texture;
};

/// The pairs of a batch list (the format `qm3d batch` reads: reference,distorted[,metric], blank
/// lines and '#' comments skipped, fields trimmed, a UTF-8 BOM ignored). A first line naming any
/// of the columns reference, distorted, metric, ref_texture, dist_texture (any case) is a header,
/// and the rows are read by its names, in its order. `name` names the file in errors. Throws FormatError for a malformed
/// line, a header with another column name or a repeated one, or a list without pairs.
std::vector<ListPair> parse_pair_list(const std::string& text, const std::string& name);

/// What identifies a result row: its first three columns.
struct ResultKey {
  std::string reference, distorted, metric;
  bool operator<(const ResultKey& o) const;
  bool operator==(const ResultKey& o) const;
};

/// A results CSV written by `qm3d batch`: its name (for messages) and its content.
struct ResultFile {
  std::string name;
  std::string text;
};

/// The outcome of merge_results. Problems are one-line messages naming the file or the pair.
struct MergeResult {
  std::string header;             ///< the shared header line
  std::vector<std::string> rows;  ///< one line per expected key found, in expected order
  std::vector<std::string> missing;    ///< expected keys no file has a row for
  std::vector<std::string> conflicts;  ///< keys with rows that differ beyond `seconds`
  std::vector<std::string> duplicates; ///< keys with several identical rows (one kept)
  std::vector<std::string> failed;     ///< kept rows whose status is not "ok", with their error
  std::vector<std::string> unexpected; ///< rows whose key is not expected (dropped)
  std::vector<std::string> warnings;   ///< e.g. an incomplete last line (a killed batch)
  std::size_t files = 0, rows_read = 0;
};

/// Joins result files into the rows of `expected` (the keys a single batch over the whole list
/// writes, in its order; a key listed k times may have k identical rows without a warning).
/// Rows of one key are the same when every column but `seconds` is equal. A kept row whose
/// status is ok but whose score is neither a finite number nor inf becomes an error row saying so
/// (and is listed in `failed`). Throws FormatError naming the file for a file without header,
/// headers that differ, a row whose number of columns differs from its header's, or rows whose
/// `settings` column (batch_results.h) differs.
MergeResult merge_results(const std::vector<ResultKey>& expected,
                          const std::vector<ResultFile>& files);

/// "reference, distorted, metric" for messages.
std::string describe(const ResultKey& key);

}  // namespace qm3d::study
