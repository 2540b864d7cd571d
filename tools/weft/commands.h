#pragma once
/// @file
/// The subcommands of `weft`. Each returns the process exit code (cli_args.h) and throws
/// `UsageError` for command-line mistakes found late (an unknown backend) and `weft::Error` for
/// bad scenes or unwritable output; main.cpp turns those into messages and exit codes 2 and 1.

#include <ostream>

#include "cli_args.h"

namespace weft::cli {

/// `weft run`: summary and output locations on `out`; progress bar, warnings and errors on `err`.
int run_command(const RunOptions& options, std::ostream& out, std::ostream& err);
/// `weft bench`: the table on `out`, progress lines on `err`.
int bench_command(const BenchOptions& options, std::ostream& out, std::ostream& err);
/// `weft view`: a window until Esc/Q or --frames; a summary line on `out`, errors on `err`. Throws
/// weft::Error when the build has no renderer or there is no display.
int view_command(const ViewOptions& options, std::ostream& out, std::ostream& err);
/// `weft edit`: the editor until Esc/Q, --frames or the script's end; a summary on `out`, failed
/// expectations and errors on `err`. Throws weft::Error when the build has no editor, the script
/// is bad, or there is no display.
int edit_command(const EditOptions& options, std::ostream& out, std::ostream& err);
/// `weft info`.
int info_command(std::ostream& out);

}  // namespace weft::cli
