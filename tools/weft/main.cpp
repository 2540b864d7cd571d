// The `weft` command: parse, dispatch, and map failures to exit codes (cli_args.h).
#include <exception>
#include <iostream>
#include <string_view>
#include <vector>

#include "weft/error.h"

#include "build_info.h"
#include "cli_args.h"
#include "commands.h"
#include "scene_keys_help.h"
#include "usage.h"

#if WEFT_HAVE_ASSETS
#include "weft/assets/assimp_loader.h"
#endif
#if WEFT_HAVE_CUDA_BACKEND
#include "weft/cuda/cuda_backend.h"
#endif

namespace {

int dispatch(const weft::cli::Invocation& inv) {
    using Command = weft::cli::Invocation::Command;
    switch (inv.command) {
        case Command::Help:
            if (inv.help_topic == weft::cli::kSceneKeysTopic)
                std::cout << (inv.help_markdown ? weft::cli::scene_keys_markdown() : weft::cli::scene_keys_text());
            else
                std::cout << weft::cli::usage_text(inv.help_topic);
            return weft::cli::kExitOk;
        case Command::Version:
            std::cout << "weft " << weft::cli::build_info().version << '\n';
            return weft::cli::kExitOk;
        case Command::Run:
            return weft::cli::run_command(inv.run, std::cout, std::cerr);
        case Command::Bench:
            return weft::cli::bench_command(inv.bench, std::cout, std::cerr);
        case Command::View:
            return weft::cli::view_command(inv.view, std::cout, std::cerr);
        case Command::Edit:
            return weft::cli::edit_command(inv.edit, std::cout, std::cerr);
        case Command::Info:
            return weft::cli::info_command(std::cout);
    }
    return weft::cli::kExitError;
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string_view> args(argv + 1, argv + argc);
    try {
#if WEFT_HAVE_ASSETS
        weft::assets::install_mesh_loader();
#endif
#if WEFT_HAVE_CUDA_BACKEND
        weft::cuda::register_cuda_backend();
#endif
        return dispatch(weft::cli::parse_command_line(args));
    } catch (const weft::cli::UsageError& e) {
        const std::string prefix = e.command().empty() ? "weft: " : "weft " + e.command() + ": ";
        std::cerr << prefix << e.what() << '\n' << weft::cli::usage_hint(e.command()) << '\n';
        return weft::cli::kExitUsage;
    } catch (const weft::Error& e) {
        std::cerr << "weft: error: " << e.what() << '\n';
        return weft::cli::kExitError;
    } catch (const std::exception& e) {
        // Not expected (I/O failures surface as weft::Error); report rather than abort.
        std::cerr << "weft: unexpected error: " << e.what() << '\n';
        return weft::cli::kExitError;
    }
}
