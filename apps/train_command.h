// `qm3d train`: reads features and subjective scores, runs the subset search with
// leave-one-group-out cross-validation (qm3d::train_linear_model) and writes the model file.
#pragma once

#include "eval_commands.h"

namespace qm3d::app {

/// Runs `qm3d train`; returns the exit code. Throws InputError / FormatError / NumericError
/// naming the file or column at fault.
int run_train(const TrainCommandOptions& options, bool quiet);

}  // namespace qm3d::app
