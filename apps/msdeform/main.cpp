// msdeform: command-line front end of the msdeform library.
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <string_view>
#include <system_error>

#include "apps/msdeform/commands.h"
#include "msdeform/core/blas_kernels.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/version.h"

namespace {

// Checks the parser makes for every command, so that their failures are usage errors (exit 2) like any other
// value outside an option's range. NaN passes CLI11's ranges (every comparison with it is false), and
// strtod reads infinities and C's hexadecimal numbers: floating-point options refuse them. --resolution
// (a string such as 100k) is read as the scenes will read it.
void add_common_checks(CLI::App& app) {
  const CLI::Validator finite(
      [](std::string& text) -> std::string {
        return msd::cli::decimal_number(text) ? std::string() : "'" + text + "' is not a finite decimal number";
      },
      "", "finite decimal");
  const CLI::Validator resolution(
      [](std::string& text) -> std::string {
        try {
          msd::parse_resolution(text);
        } catch (const msd::Error& e) {
          return e.what();
        }
        return {};
      },
      "", "resolution");
  // Integers are decimal too: CLI11 reads 010 as octal 8 and 0x10 as 16, and calls 08 or 2.5 "not in range".
  // Written without leading zeros (which CLI11 would read as octal) before the ranges check them.
  const CLI::Validator decimal_integer(
      [](std::string& text) -> std::string {
        const size_t digits = text.find_first_not_of("+-") == 1 ? 1 : 0;
        if (text.size() == digits || text.find_first_not_of("0123456789", digits) != std::string::npos)
          return "'" + text + "' is not a whole decimal number";
        const size_t first = std::min(text.find_first_not_of('0', digits), text.size() - 1);
        text = text.substr(0, digits) + text.substr(first);
        return {};
      },
      "", "decimal integer");
  for (CLI::Option* option : app.get_options()) {
    const std::string type = option->get_type_name();
    if (type.find("FLOAT") != std::string::npos)
      option->check(finite);
    else if (type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0)
      option->transform(decimal_integer);
    if (option->get_name() == "--resolution") option->check(resolution);
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) add_common_checks(*sub);
}

// OpenBLAS starts its worker thread as it loads, and the worker takes its 128 MB work buffer at once,
// retrying forever where an address-space limit (ulimit -v) leaves no room: the process then spins on a
// core and hangs at exit (measured: `msdeform --version` under 300 MB). Under any limit the tool runs
// itself again, once, with OPENBLAS_NUM_THREADS=1 (no worker); the factorisation asks for the room its
// own BLAS calls need (blas_room()). Returns where exec fails or is not needed.
void rerun_without_blas_worker_under_a_limit(char** argv) {
  rlimit limit;
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY ||
      std::getenv("OPENBLAS_NUM_THREADS") || msd::blas_kernels().empty())
    return;
  setenv("OPENBLAS_NUM_THREADS", "1", 1);
  execv("/proc/self/exe", argv);
  unsetenv("OPENBLAS_NUM_THREADS");
}

// A thread that could not start (TBB's "pthread_create has failed", std::thread's EAGAIN):
// the process ran out of address space or of processes, not a fault of the program.
bool thread_start_failed(const std::exception& e) {
  if (const auto* s = dynamic_cast<const std::system_error*>(&e))
    return s->code() == std::errc::resource_unavailable_try_again;
  return std::string_view(e.what()).find("pthread_create") != std::string_view::npos;
}

// "--def is not an option of decompose (deform, compare, view take it)" for the first option on the command
// line that the chosen subcommand lacks and others have (CLI11 says only "The following arguments were
// not expected"), else "".
std::string misplaced_option(CLI::App& app, int argc, char** argv) {
  const std::vector<CLI::App*> chosen = app.get_subcommands();
  if (chosen.size() != 1) return {};
  for (int i = 2; i < argc && std::string_view(argv[i]) != "--"; ++i) {
    const std::string arg = argv[i], name = arg.substr(0, arg.find('='));
    if (name.size() < 3 || name.rfind("--", 0) != 0 || chosen[0]->get_option_no_throw(name)) continue;
    std::string others;
    for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
      if (sub != chosen[0] && sub->get_option_no_throw(name))
        others += (others.empty() ? "" : ", ") + sub->get_name();
    if (!others.empty())
      return name + " is not an option of " + chosen[0]->get_name() + " (" + others + " take" +
             (others.find(',') == std::string::npos ? "s" : "") + " it)";
  }
  return {};
}

}  // namespace

std::optional<double> msd::cli::decimal_number(const std::string& text) {
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);  // overflow gives ±inf; underflow a finite tiny value
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(x) ||
      text.find_first_of("xX") != std::string::npos)
    return std::nullopt;
  return x;
}

int main(int argc, char** argv) {
  rerun_without_blas_worker_under_a_limit(argv);
  msd::retain_freed_memory();
  msd::select_blas_kernels();  // before any thread uses BLAS (core/blas_kernels.h)
  CLI::App app{"msdeform: multi-scale, detail-preserving deformation of triangle meshes"};
  app.require_subcommand(1);
  app.footer(
      "The performance figures (prepare, frame, memory per method at a chosen size): bench/run in the "
      "source tree (README, Benchmarks).");
  app.set_help_all_flag("--help-all", "Print help for all subcommands");
  app.set_version_flag("--version", [] {
    return std::string("msdeform ") + msd::version() + "\n" + msd::build_info() +
           "\nLicence GPL-3.0-or-later (see LICENSE; CGAL's Polygon Mesh Processing is GPL-3.0-or-later)";
  });
  msd::cli::add_info_command(app);
  msd::cli::add_scene_command(app);
  msd::cli::add_deform_command(app);
  msd::cli::add_decompose_command(app);
  msd::cli::add_compare_command(app);
  msd::cli::add_render_command(app);
  msd::cli::add_view_command(app);
  add_common_checks(app);
  // CLI11 takes "--name=" with nothing after the '=' as a missing value and reads the next argument in its
  // place: the error would then name that argument, or a flag's value would be swallowed.
  for (int i = 1; i < argc && std::string_view(argv[i]) != "--"; ++i)
    if (const std::string_view arg = argv[i];
        arg.size() > 3 && arg.substr(0, 2) == "--" && arg.back() == '=') {
      std::cerr << arg << ": no value after '='\nRun with --help or --help-all for more information.\n";
      return 2;
    }
  // CLI11 reports an unknown first word as a missing subcommand.
  if (argc > 1 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      known = known || sub->check_name(argv[1]);
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::cerr
          << "unknown subcommand '" << argv[1] << "'; the subcommands are " << names
          << " (the benchmarks are bench/run in the source tree)\nRun with --help for more information.\n";
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // An option of another subcommand is the cause of whatever CLI11 reports (an unexpected argument, or
    // its value taken for the mesh: "mesh excludes --scene").
    if (const std::string hint = e.get_exit_code() != 0 ? misplaced_option(app, argc, argv) : std::string();
        !hint.empty()) {
      std::cerr << hint << "\nRun with --help or --help-all for more information.\n";
      return 2;
    }
    // --help and --version exit 0; a usage error (unknown option, bad value) exits 2, as other tools do.
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const msd::Error& e) {
    std::cerr << "msdeform: error: " << msd::out_of_memory_message(e.what()) << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "msdeform: error: " << msd::out_of_memory_message("out of memory") << "\n";
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {  // a path that cannot even be examined
    std::cerr << "msdeform: error: " << e.path1().string() << ": " << e.code().message() << "\n";
    return 1;
  } catch (const std::exception& e) {
    if (thread_start_failed(e)) {
      std::cerr << "msdeform: error: a worker thread could not start (" << e.what()
                << "): raise the address-space limit (ulimit -v) or the process limit (ulimit -u)\n";
      return 1;
    }
    std::cerr << "msdeform: internal error: " << e.what() << " (please report it with the command line)\n";
    return 70;  // EX_SOFTWARE
  }
  return 0;
}
