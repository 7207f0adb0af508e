#include "batch_options.h"

#include <cstdint>
#include <string>

namespace qm3d::app {

void add_batch_safety_options(CLI::App* batch_cmd, study::BatchOptions& o) {
  batch_cmd->add_flag("--retry-failed", o.retry_failed,
                      "With --resume: score the rows that record an error again (their old rows "
                      "are replaced)");
  auto* timeout =
      batch_cmd
          ->add_option("--pair-timeout", o.pair_timeout_s,
                       "Stop scoring a pair after this many seconds; its row records the "
                       "timeout (default: no limit; over 1e9 s, inf included: no limit)")
          ->check(CLI::Validator(
              [](std::string& text) {
                // CLI::PositiveNumber lets "nan" through (NaN <= 0 is false).
                double v = 0;
                const bool number = CLI::detail::lexical_cast(text, v);
                return number && v > 0 ? std::string()
                                       : "a number of seconds > 0 needed, not \"" + text + "\"";
              },
              "SECONDS > 0"))
          ->type_name("SECONDS");
  batch_cmd
      ->add_flag_function(
          "--no-isolation", [&o](std::int64_t) { o.isolate = false; },
          "Score the pairs inside this process instead of in worker processes (one per job, "
          "restarted after a pair that crashed): saves a few milliseconds per pair, but a pair "
          "that crashes ends the batch")
      ->excludes(timeout);
}

}  // namespace qm3d::app
