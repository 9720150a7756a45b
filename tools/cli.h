// Command lines of the tools (boost::program_options): every tool answers --help with its usage
// and options, and a bad option or value ends in one clear error line and exit code 2, never in
// an uncaught exception or a silently wrong default.
#pragma once

#include <boost/program_options.hpp>
#include <cstdlib>
#include <iostream>
#include <string>

namespace vi_ekf_slam::cli {

namespace po = boost::program_options;

/// Parses argv into vm. --help prints `about`, the usage line and the options and exits 0; an
/// error prints it with the usage line and exits 2. `positional` may be empty.
inline po::variables_map parse(int argc, char** argv, const std::string& usage, const std::string& about,
                               po::options_description options,
                               const po::positional_options_description& positional = {}) {
  options.add_options()("help,h", "print this help and exit");
  po::variables_map vm;
  try {
    // No guessing of abbreviations: "--minute 1" is an error, not the 1-minute run of --minutes.
    const int style = po::command_line_style::default_style & ~po::command_line_style::allow_guessing;
    po::store(po::command_line_parser(argc, argv).options(options).positional(positional).style(style).run(), vm);
    if (vm.count("help")) {
      std::cout << about << "\n\nusage: " << usage << "\n\n" << options << "\n";
      std::exit(0);
    }
    po::notify(vm);
  } catch (const po::error& e) {
    std::cerr << "error: " << e.what() << "\nusage: " << usage << "\n(--help for the options)\n";
    std::exit(2);
  }
  return vm;
}

/// A usage error found after parsing (a value out of its range): message, usage line, exit 2.
[[noreturn]] inline void fail(const std::string& usage, const std::string& message) {
  std::cerr << "error: " << message << "\nusage: " << usage << "\n(--help for the options)\n";
  std::exit(2);
}

}  // namespace vi_ekf_slam::cli
