// Tests of apps/shard.h: --shard K/N parsing, the size-balanced partition and the merge of shard
// results.
#include "qm3d/study/shard.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <set>
#include <stdexcept>

#include "qm3d/common/error.h"

namespace qm3d::study {
namespace {

// 20 pair sizes with repeats (ties), zeros (missing files) and a wide range.
std::vector<std::uintmax_t> twenty_sizes() {
  return {500, 20, 0, 7000, 20, 133, 9000, 0, 64, 4096, 20, 800, 800, 1, 77777, 3, 500, 12, 0, 5};
}

TEST(ParseShard, AcceptsKOfN) {
  const Shard s = parse_shard("2/5");
  EXPECT_EQ(s.index, 2u);
  EXPECT_EQ(s.count, 5u);
  EXPECT_EQ(parse_shard("0/1").count, 1u);
  EXPECT_EQ(parse_shard("99/100").index, 99u);
}

TEST(ParseShard, RejectsBadText) {
  for (const char* bad : {"", "3", "/", "1/", "/3", "3/3", "4/3", "1/0", "0/0", "-1/3", "1/-3",
                          "+1/3", " 1/3", "1/3 ", "a/3", "1/b", "1.5/3", "1/3/5", "1e2/300",
                          "99999999999999999999/3"}) {
    EXPECT_THROW(parse_shard(bad), std::invalid_argument) << '"' << bad << '"';
  }
}

TEST(ParseShard, MessagesSayWhatIsWrong) {
  const auto message = [](const std::string& text) {
    try {
      parse_shard(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_EQ(message("3/3"), "\"3/3\": K must be below N (shards are numbered 0..2, as "
                            "SLURM_ARRAY_TASK_ID with --array=0-2)");
  EXPECT_NE(message("x").find("expected K/N"), std::string::npos);
  EXPECT_NE(message("1/0").find("N must be at least 1"), std::string::npos);
  EXPECT_NE(message("a/2").find("K must be a whole number"), std::string::npos);
}

TEST(Partition, DisjointCompleteAndDeterministicForOneToSevenShards) {
  const auto sizes = twenty_sizes();
  for (std::size_t n = 1; n <= 7; ++n) {
    const auto parts = partition_by_size(sizes, n);
    ASSERT_EQ(parts.size(), n);
    std::vector<int> seen(sizes.size(), 0);
    for (std::size_t k = 0; k < n; ++k) {
      EXPECT_TRUE(std::is_sorted(parts[k].begin(), parts[k].end()));
      EXPECT_EQ(shard_rows(sizes, {k, n}), parts[k]) << k << "/" << n;
      for (const std::size_t row : parts[k]) ++seen[row];
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(sizes.size())) << n;
    EXPECT_EQ(partition_by_size(sizes, n), parts) << "not deterministic for N = " << n;
  }
}

TEST(Partition, FollowsLongestProcessingTimeWithTiesToLowIndices) {
  // Sizes 5, 9, 5, 1 in 2 parts: 9 -> part 0; 5 (row 0) -> part 1; 5 (row 2) -> part 1 (5 < 9);
  // 1 -> part 0 (9 < 10).
  const auto parts = partition_by_size({5, 9, 5, 1}, 2);
  EXPECT_EQ(parts[0], (std::vector<std::size_t>{1, 3}));
  EXPECT_EQ(parts[1], (std::vector<std::size_t>{0, 2}));
  // Equal sizes: round robin in list order.
  const auto even = partition_by_size({7, 7, 7, 7, 7, 7}, 3);
  EXPECT_EQ(even[0], (std::vector<std::size_t>{0, 3}));
  EXPECT_EQ(even[1], (std::vector<std::size_t>{1, 4}));
  EXPECT_EQ(even[2], (std::vector<std::size_t>{2, 5}));
}

TEST(Partition, BalancesBySize) {
  // One huge pair and many small ones: the huge pair is alone in its part.
  std::vector<std::uintmax_t> sizes(20, 10);
  sizes[13] = 1000;
  const auto parts = partition_by_size(sizes, 4);
  for (const auto& p : parts) {
    if (std::find(p.begin(), p.end(), 13u) != p.end()) {
      EXPECT_EQ(p.size(), 1u);
    }
  }
  // Greedy LPT: no part exceeds the mean by more than the largest pair.
  const auto mixed = twenty_sizes();
  const std::uintmax_t total = std::accumulate(mixed.begin(), mixed.end(), std::uintmax_t{0});
  const std::uintmax_t largest = *std::max_element(mixed.begin(), mixed.end());
  for (std::size_t n = 1; n <= 7; ++n) {
    for (const auto& p : partition_by_size(mixed, n)) {
      std::uintmax_t load = 0;
      for (const std::size_t row : p) load += mixed[row];
      EXPECT_LE(load, total / n + largest) << n;
    }
  }
  // Without the one large pair, equal counts of equal pairs.
  const auto equal = partition_by_size(std::vector<std::uintmax_t>(20, 3), 7);
  for (const auto& p : equal) EXPECT_TRUE(p.size() == 2 || p.size() == 3);
}

TEST(Partition, MoreShardsThanRowsLeavesSomeEmpty) {
  const auto parts = partition_by_size({1, 2}, 5);
  EXPECT_EQ(parts[0], (std::vector<std::size_t>{1}));
  EXPECT_EQ(parts[1], (std::vector<std::size_t>{0}));
  for (std::size_t k = 2; k < 5; ++k) EXPECT_TRUE(parts[k].empty());
}

TEST(Partition, SelectShardKeepsListOrder) {
  const std::vector<std::string> rows = {"a", "bbbb", "cc", "ddd"};
  const auto size = [](const std::string& s) { return std::uintmax_t(s.size()); };
  EXPECT_EQ(select_shard(rows, {0, 2}, size), (std::vector<std::string>{"a", "bbbb"}));
  EXPECT_EQ(select_shard(rows, {1, 2}, size), (std::vector<std::string>{"cc", "ddd"}));
  EXPECT_EQ(select_shard(rows, {0, 1}, size), rows);
}

TEST(InputBytes, MissingFileCountsAsZero) {
  EXPECT_EQ(input_bytes("/nonexistent/qm3d/file.ply"), 0u);
  EXPECT_EQ(input_bytes("/"), 0u);  // a directory
}

TEST(PairList, ReadsLikeBatch) {
  const auto pairs = parse_pair_list(
      "reference,distorted,metric\n# comment\n\n a.ply , b.ply \nc.off,d.off,compare\r\n"
      "\"e,1.ply\",f.ply,\n",
      "list.csv");
  ASSERT_EQ(pairs.size(), 3u);
  EXPECT_EQ(pairs[0].reference, "a.ply");
  EXPECT_EQ(pairs[0].distorted, "b.ply");
  EXPECT_EQ(pairs[0].metric, "auto");
  EXPECT_EQ(pairs[1].metric, "compare");
  EXPECT_EQ(pairs[2].reference, "e,1.ply");
  EXPECT_EQ(pairs[2].metric, "auto");
  EXPECT_THROW(parse_pair_list("# only a comment\n", "list.csv"), FormatError);
  try {
    parse_pair_list("a.ply,b.ply\nonly_one\n", "list.csv");
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_STREQ(e.what(), "list.csv: line 2: expected reference,distorted[,metric]");
  }
}

TEST(PairList, HeaderNamesTheColumnsAndABomIsIgnored) {
  const auto pairs = parse_pair_list(
      "\xEF\xBB\xBF"
      "Distorted,metric,reference\nb.ply,pcqm,a.ply\n",
      "list.csv");
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].reference, "a.ply");
  EXPECT_EQ(pairs[0].distorted, "b.ply");
  EXPECT_EQ(pairs[0].metric, "pcqm");
  const auto no_metric = parse_pair_list("distorted,reference\nb.ply,a.ply\n", "list.csv");
  EXPECT_EQ(no_metric[0].reference, "a.ply");
  EXPECT_EQ(no_metric[0].metric, "auto");
  try {
    parse_pair_list("reference,distorted,weight\na,b,1\n", "list.csv");
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("list.csv: line 1: unknown column \"weight\""),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(parse_pair_list("reference,reference\na,b\n", "list.csv"), FormatError);
  EXPECT_THROW(parse_pair_list("metric,distorted\ncmdm,b\n", "list.csv"), FormatError);
}

// ---- merge -------------------------------------------------------------------------------

const char* const kHeader = "reference,distorted,metric,score,status,error,seconds,f1";

std::string row(const std::string& ref, const std::string& metric, const std::string& score,
                const std::string& seconds = "1.5") {
  return ref + ",d.ply," + metric + "," + score + ",ok,," + seconds + ",0.25";
}

ResultFile file(const std::string& name, const std::vector<std::string>& rows) {
  std::string text = std::string(kHeader) + "\n";
  for (const auto& r : rows) text += r + "\n";
  return {name, text};
}

std::vector<ResultKey> keys(const std::vector<std::pair<std::string, std::string>>& refs_metrics) {
  std::vector<ResultKey> k;
  for (const auto& [ref, metric] : refs_metrics) k.push_back({ref, "d.ply", metric});
  return k;
}

TEST(Merge, RowsInExpectedOrderWhateverTheFileOrder) {
  const auto expected = keys({{"a", "cmdm"}, {"b", "cmdm"}, {"b", "msdm2"}, {"b", "pcqm"},
                              {"c", "pcqm"}});
  const MergeResult m = merge_results(
      expected, {file("OUT_1.csv", {row("c", "pcqm", "3"), row("a", "cmdm", "1")}),
                 file("OUT_0.csv", {row("b", "pcqm", "2.3"), row("b", "cmdm", "2.1"),
                                    row("b", "msdm2", "2.2")})});
  EXPECT_EQ(m.header, kHeader);
  EXPECT_EQ(m.rows, (std::vector<std::string>{row("a", "cmdm", "1"), row("b", "cmdm", "2.1"),
                                              row("b", "msdm2", "2.2"), row("b", "pcqm", "2.3"),
                                              row("c", "pcqm", "3")}));
  EXPECT_TRUE(m.missing.empty());
  EXPECT_TRUE(m.duplicates.empty());
  EXPECT_TRUE(m.conflicts.empty());
  EXPECT_TRUE(m.failed.empty());
  EXPECT_EQ(m.rows_read, 5u);
}

TEST(Merge, ReportsMissingRows) {
  const MergeResult m = merge_results(keys({{"a", "cmdm"}, {"b", "cmdm"}, {"c", "cmdm"}}),
                                      {file("OUT_0.csv", {row("b", "cmdm", "2")}),
                                       file("OUT_1.csv", {})});
  EXPECT_EQ(m.rows, (std::vector<std::string>{row("b", "cmdm", "2")}));
  EXPECT_EQ(m.missing, (std::vector<std::string>{"a, d.ply, cmdm", "c, d.ply, cmdm"}));
}

TEST(Merge, IdenticalDuplicatesKeepOneAndWarn) {
  // Same result, different seconds: the same row.
  const MergeResult m = merge_results(
      keys({{"a", "cmdm"}}), {file("OUT_0.csv", {row("a", "cmdm", "1", "2.5")}),
                              file("OUT_1.csv", {row("a", "cmdm", "1", "9.75")})});
  EXPECT_EQ(m.rows, (std::vector<std::string>{row("a", "cmdm", "1", "2.5")}));
  ASSERT_EQ(m.duplicates.size(), 1u);
  EXPECT_NE(m.duplicates[0].find("OUT_0.csv:2, OUT_1.csv:2"), std::string::npos);
  EXPECT_TRUE(m.conflicts.empty());
}

TEST(Merge, PairListedTwiceMayHaveTwoRowsSilently) {
  const MergeResult m = merge_results(
      keys({{"a", "cmdm"}, {"a", "cmdm"}}),
      {file("OUT_0.csv", {row("a", "cmdm", "1")}), file("OUT_1.csv", {row("a", "cmdm", "1")})});
  EXPECT_EQ(m.rows.size(), 1u);
  EXPECT_TRUE(m.duplicates.empty());
}

TEST(Merge, ConflictingDuplicatesAreReported) {
  const MergeResult m = merge_results(
      keys({{"a", "cmdm"}, {"b", "cmdm"}}),
      {file("OUT_0.csv", {row("a", "cmdm", "1"), row("b", "cmdm", "2")}),
       file("OUT_1.csv", {row("a", "cmdm", "1.0000001")})});
  ASSERT_EQ(m.conflicts.size(), 1u);
  EXPECT_EQ(m.conflicts[0], "a, d.ply, cmdm: OUT_0.csv:2 and OUT_1.csv:2 differ");
  EXPECT_EQ(m.rows, (std::vector<std::string>{row("b", "cmdm", "2")}));
}

TEST(Merge, FailedRowsAreKeptAndListed) {
  const std::string failed = "a,d.ply,cmdm,,error,a: no such file,,";
  const MergeResult m = merge_results(keys({{"a", "cmdm"}}), {file("OUT_0.csv", {failed})});
  EXPECT_EQ(m.rows, (std::vector<std::string>{failed}));
  EXPECT_EQ(m.failed, (std::vector<std::string>{"a, d.ply, cmdm: a: no such file"}));
}

TEST(Merge, UnexpectedRowsAreDroppedAndListed) {
  const MergeResult m = merge_results(
      keys({{"a", "cmdm"}}), {file("OUT_0.csv", {row("a", "cmdm", "1"), row("z", "pcqm", "9")})});
  EXPECT_EQ(m.rows.size(), 1u);
  EXPECT_EQ(m.unexpected, (std::vector<std::string>{"z, d.ply, pcqm (OUT_0.csv:3)"}));
}

TEST(Merge, IncompleteLastLineIsIgnoredWithAWarning) {
  ResultFile f = file("OUT_0.csv", {row("a", "cmdm", "1")});
  f.text += "b,d.ply,cm";  // a task killed in the middle of a write
  const MergeResult m = merge_results(keys({{"a", "cmdm"}, {"b", "cmdm"}}), {f});
  EXPECT_EQ(m.rows.size(), 1u);
  EXPECT_EQ(m.missing, (std::vector<std::string>{"b, d.ply, cmdm"}));
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_NE(m.warnings[0].find("OUT_0.csv:3: incomplete last line"), std::string::npos);
}

TEST(Merge, RejectsFilesThatAreNotBatchResults) {
  const auto expected = keys({{"a", "cmdm"}});
  EXPECT_THROW(merge_results(expected, {{"empty.csv", ""}}), FormatError);
  EXPECT_THROW(merge_results(expected, {{"other.csv", "x,y,z\n1,2,3\n"}}), FormatError);
  try {
    merge_results(expected, {file("OUT_0.csv", {}), {"OUT_1.csv", "reference,distorted,metric,"
                                                                  "score,status,error,seconds\n"}});
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_STREQ(e.what(), "OUT_1.csv: header differs from OUT_0.csv's (results of another qm3d "
                           "version?)");
  }
  try {
    merge_results(expected, {file("OUT_0.csv", {"a,d.ply,cmdm,1,ok"})});
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_STREQ(e.what(), "OUT_0.csv: line 2: 5 columns, the header has 8");
  }
}

TEST(Merge, ANonNumberScoreWithStatusOkIsAnErrorRow) {
  const MergeResult m =
      merge_results(keys({{"a", "cmdm"}, {"b", "cmdm"}}),
                    {file("OUT_0.csv", {row("a", "cmdm", "garbage"), row("b", "cmdm", "")})});
  ASSERT_EQ(m.rows.size(), 2u);
  ASSERT_EQ(m.failed.size(), 2u);
  EXPECT_EQ(
      m.rows[0],
      "a,d.ply,cmdm,,error,\"merge: status ok but the score \"\"garbage\"\" is not a score (a "
      "finite number or inf) (OUT_0.csv:2)\",1.5,0.25");
}

// What batch writes is kept: "inf" (PSNR of identical inputs, issue 37); nan and -inf never are.
TEST(Merge, AnInfScoreIsKeptNanAndMinusInfAreErrors) {
  const MergeResult m = merge_results(
      keys({{"a", "psnr"}, {"b", "psnr"}, {"c", "psnr"}}),
      {file("OUT_0.csv",
            {row("a", "psnr", "inf"), row("b", "psnr", "nan"), row("c", "psnr", "-inf")})});
  ASSERT_EQ(m.rows.size(), 3u);
  EXPECT_EQ(m.rows[0], row("a", "psnr", "inf"));
  ASSERT_EQ(m.failed.size(), 2u);
  EXPECT_NE(m.rows[1].find("\"\"nan\"\" is not a score"), std::string::npos) << m.rows[1];
  EXPECT_NE(m.rows[2].find("\"\"-inf\"\" is not a score"), std::string::npos) << m.rows[2];
}

TEST(Merge, RowsScoredWithOtherSettingsAreRefused) {
  const auto with_settings = [](const std::string& name, const std::string& settings) {
    return ResultFile{name, std::string(kHeader) + ",settings\n" + row("a", "cmdm", "0.5") + "," +
                                settings + "\n"};
  };
  EXPECT_NO_THROW(merge_results(keys({{"a", "cmdm"}}), {with_settings("OUT_0.csv", "defaults"),
                                                        with_settings("OUT_1.csv", "defaults")}));
  EXPECT_THROW(merge_results(keys({{"a", "cmdm"}}), {with_settings("OUT_0.csv", "defaults"),
                                                     with_settings("OUT_1.csv", "radius=0.01")}),
               FormatError);
}

}  // namespace
}  // namespace qm3d::study
