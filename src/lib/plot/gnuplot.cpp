// Running gnuplot: one child process fed the whole script (data blocks inline) on its stdin.
#include "plot/gnuplot.hpp"

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <mutex>
#include <sstream>
#include <thread>

#include "common/error.hpp"
#include "common/tool.hpp"
#include "plot/live.hpp"
#include "plot/script.hpp"

extern char** environ;

namespace mcg::plot {

namespace {

// True when `program` names an executable file, directly or through PATH.
bool executable_exists(const std::string& program) {
  if (program.find('/') != std::string::npos) return ::access(program.c_str(), X_OK) == 0;
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    std::size_t colon = dirs.find(':', start);
    if (colon == std::string::npos) colon = dirs.size();
    const std::string dir = colon == start ? "." : dirs.substr(start, colon - start);
    const std::string candidate = dir + "/" + program;
    struct stat st {};
    if (::stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
        ::access(candidate.c_str(), X_OK) == 0) {
      return true;
    }
    start = colon + 1;
  }
  return false;
}

// A child process with a pipe to its stdin and, optionally, one from its stdout.
class Child {
 public:
  Child(const std::vector<std::string>& argv, bool capture_stdout) {
    int in[2];
    int out[2] = {-1, -1};
    if (::pipe2(in, O_CLOEXEC) != 0) fail("cannot create a pipe: {}", std::strerror(errno));
    if (capture_stdout && ::pipe2(out, O_CLOEXEC) != 0) {
      const int error = errno;
      ::close(in[0]);
      ::close(in[1]);
      fail("cannot create a pipe: {}", std::strerror(error));
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
    if (capture_stdout) posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const int rc = ::posix_spawnp(&m_pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(in[0]);
    if (capture_stdout) ::close(out[1]);
    m_in = in[1];
    m_out = out[0];
    if (rc != 0) {
      close_fds();
      fail("cannot run {}: {}", argv[0], std::strerror(rc));
    }
  }
  ~Child() {
    close_fds();
    if (m_pid > 0) wait();
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  // Writes all of `text` unless the child stops reading (then the rest is dropped: the
  // child's exit status tells what went wrong).
  void feed(const std::string& text) {
    std::size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = ::write(m_in, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
    ::close(m_in);
    m_in = -1;
  }

  // Writes all of `text` and keeps the pipe open; false when the child stopped reading.
  bool send(const std::string& text) {
    std::size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = ::write(m_in, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }

  // The child's output up to the line `marker` (consumed), waiting at most timeout_ms for it.
  std::string read_until(const std::string& marker, int timeout_ms) {
    const std::string tail = marker + "\n";
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    for (;;) {
      const std::size_t at = m_pending.find(tail);
      if (at != std::string::npos && (at == 0 || m_pending[at - 1] == '\n')) {
        std::string text = m_pending.substr(0, at);
        m_pending.erase(0, at + tail.size());
        return text;
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) fail("gnuplot did not finish a frame within {} s", timeout_ms / 1000);
      pollfd pfd{m_out, POLLIN, 0};
      const int ready = ::poll(&pfd, 1, static_cast<int>(left.count()));
      if (ready < 0 && errno == EINTR) continue;
      if (ready <= 0) continue;
      char buffer[8192];
      const ssize_t n = ::read(m_out, buffer, sizeof buffer);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) fail("gnuplot ended (exit status {})", wait());
      m_pending.append(buffer, static_cast<std::size_t>(n));
    }
  }

  std::string read_all() {
    std::string text;
    char buffer[4096];
    for (;;) {
      const ssize_t n = ::read(m_out, buffer, sizeof buffer);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      text.append(buffer, static_cast<std::size_t>(n));
    }
    return text;
  }

  // Exit status, or 128 + signal.
  int wait() {
    int status = 0;
    while (::waitpid(m_pid, &status, 0) < 0 && errno == EINTR) {
    }
    m_pid = -1;
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  }

 private:
  void close_fds() {
    if (m_in >= 0) ::close(m_in);
    if (m_out >= 0) ::close(m_out);
    m_in = m_out = -1;
  }

  pid_t m_pid = -1;
  int m_in = -1;
  int m_out = -1;
  std::string m_pending;
};

void require_gnuplot(const std::string& program) {
  if (!executable_exists(program)) {
    fail("gnuplot not found ({}; install gnuplot-nox, or set MCG_GNUPLOT)", quote(program));
  }
}

// The first interactive terminal this gnuplot offers, or a clear error.
std::string window_terminal(const std::string& program) {
  Child probe({program, "-d", "-e", "set print '-'; print GPVAL_TERMINALS"}, true);
  probe.feed("");
  const std::string text = probe.read_all();
  probe.wait();
  std::istringstream words(text);
  std::vector<std::string> terminals{std::istream_iterator<std::string>(words), {}};
  std::string found;
  for (const char* term : {"qt", "wxt", "x11"}) {
    if (std::find(terminals.begin(), terminals.end(), term) != terminals.end()) {
      found = term;
      break;
    }
  }
  if (found.empty()) {
    fail(
        "no window to plot in: this gnuplot has no interactive terminal (gnuplot-nox); use -o FILE "
        "(.png, .svg, .pdf) or --term dumb");
  }
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((display == nullptr || *display == '\0') && (wayland == nullptr || *wayland == '\0')) {
    fail("no window to plot in: DISPLAY is not set; use -o FILE (.png, .svg, .pdf) or --term dumb");
  }
  return found;
}

std::string display_label(const std::string& path) { return path == "-" ? "stdin" : printable_name(path); }

/// Seconds gnuplot may take for one frame before the tool gives up on it.
constexpr int k_frame_timeout_ms = 20000;

void run_live(const Options& o, Spec spec, const std::string& program) {
  if (spec.mode != Mode::series) fail("--live draws series against x; not with --bode, --xy or --rlocus");
  if (o.files.size() + o.overlays.size() > 1) fail("--live follows one input (a file or stdin)");
  if (!(o.window_s > 0.0) || !(o.interval_s > 0.0)) fail("--window and --interval must be positive");
  const std::string path = o.files.empty() ? "-" : o.files.front();
  std::ifstream file;
  if (path != "-") {
    file.open(path, std::ios::binary);
    if (!file) fail("{}: cannot open: {}", printable_name(path), std::strerror(errno));
  }
  std::istream& in = path == "-" ? std::cin : file;
  table::Reader reader(in, display_label(path));
  RingWindow ring(reader.columns(), reader.require(spec.x), o.window_s);
  const table::Metadata meta = reader.metadata();

  // The reader runs on its own thread, so a slow frame never holds up the input.
  std::mutex mutex;
  std::condition_variable arrived;
  bool done = false;
  std::string error;
  std::thread thread([&] {
    try {
      while (reader.next()) {
        const std::string where = fmt::format("{}:{}", reader.source(), reader.line());
        const std::lock_guard lock(mutex);
        ring.push(reader.row(), where);
      }
    } catch (const std::exception& e) {
      const std::lock_guard lock(mutex);
      error = e.what();
    }
    const std::lock_guard lock(mutex);
    done = true;
    arrived.notify_all();
  });
  struct Joiner {
    std::thread& t;
    ~Joiner() {
      if (t.joinable()) t.join();
    }
  } joiner{thread};

  const std::string final_path = spec.output.path;
  const std::string part_path = final_path + ".part";
  if (spec.output.kind == Output::Kind::png) spec.output.path = part_path;
  std::vector<std::string> argv{program, "-d"};
  if (spec.output.kind == Output::Kind::window) argv.emplace_back("-persist");
  Child gnuplot(argv, true);
  const bool tty = spec.output.kind == Output::Kind::dumb && ::isatty(STDOUT_FILENO) != 0;
  std::size_t drawn = 0;
  std::size_t frame = 0;
  // Frames are due on a fixed grid of --interval, so drawing one does not delay the next; one
  // that took longer than the interval is followed at once.
  const auto interval = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(o.interval_s));
  auto due = std::chrono::steady_clock::now();
  for (;;) {
    bool finished = false;
    table::Table window;
    due = std::max(due + interval, std::chrono::steady_clock::now());
    {
      std::unique_lock lock(mutex);
      arrived.wait_until(lock, due, [&] { return done; });
      finished = done;
      if (ring.pushed() == drawn && !finished) continue;
      if (ring.size() > 0 && ring.pushed() != drawn) window = ring.table(reader.source(), meta);
      drawn = ring.pushed();
    }
    if (window.rows() > 0) {
      ++frame;
      const std::string marker = fmt::format("mcg-frame-{}", frame);
      const std::string script = "reset\n" + build_script(spec, {{std::move(window), display_label(path)}}) +
                                 "set print '-'\nprint '" + marker + "'\n";
      if (!gnuplot.send(script)) fail("gnuplot ended (exit status {})", gnuplot.wait());
      const std::string text = gnuplot.read_until(marker, k_frame_timeout_ms);
      if (spec.output.kind == Output::Kind::png) {
        if (std::rename(part_path.c_str(), final_path.c_str()) != 0) {
          fail("-o {}: cannot replace: {}", printable_name(final_path), std::strerror(errno));
        }
      } else if (spec.output.kind == Output::Kind::dumb) {
        // On a terminal each frame replaces the last (cursor home, clear to the end).
        std::cout << (tty ? "\x1b[H\x1b[J" : "") << text << std::flush;
      }
    }
    if (finished) break;
  }
  thread.join();
  if (!error.empty()) throw Error(error);
}

}  // namespace

std::string gnuplot_program() {
  const char* env = std::getenv("MCG_GNUPLOT");
  return env != nullptr && *env != '\0' ? env : "gnuplot";
}

void run(const Options& o) {
  Spec spec;
  spec.mode = o.bode ? Mode::bode : (o.xy ? Mode::xy : (o.rlocus ? Mode::rlocus : Mode::series));
  spec.x = o.x;
  spec.y = o.y;
  spec.y2 = o.y2;
  spec.steps = o.steps;
  spec.logx = o.logx;
  spec.logy = o.logy;
  spec.title = o.title;

  const bool text = o.term == "dumb";
  if (!o.output.empty() && text) fail("-o and --term dumb exclude each other");
  const std::string program = gnuplot_program();
  const bool plot = !o.output.empty() || text || o.script.empty();
  if (!o.output.empty()) {
    spec.output.kind = kind_from_path(o.output);
    // gnuplot reads an output name starting with '|' as a command to pipe into.
    spec.output.path = o.output.front() == '|' ? "./" + o.output : o.output;
  } else if (text) {
    spec.output.kind = Output::Kind::dumb;
  }
  if (plot) require_gnuplot(program);
  if (plot && spec.output.kind == Output::Kind::none) {
    spec.output.kind = Output::Kind::window;
    spec.output.window_term = window_terminal(program);
  }
  if (o.live && !o.script.empty()) fail("--script writes one script; not with --live");
  if (o.live && !plot) fail("--live draws: give -o FILE.png, --term dumb, or a window (no --script alone)");
  if (o.live && spec.output.kind != Output::Kind::png && spec.output.kind != Output::Kind::dumb &&
      spec.output.kind != Output::Kind::window) {
    fail("--live rewrites a PNG, a text plot or a window; not {}", printable_name(o.output));
  }
  const bool tall = spec.mode == Mode::bode || spec.mode == Mode::rlocus;
  if (text) {
    spec.output.width = o.size ? (*o.size)[0] : 100;
    spec.output.height = o.size ? (*o.size)[1] : (tall ? 44 : 30);
  } else {
    spec.output.width = o.size ? (*o.size)[0] : 1000;
    spec.output.height = o.size ? (*o.size)[1] : (tall ? 800 : 600);
  }

  if (o.live) {
    run_live(o, spec, program);
    return;
  }
  std::vector<std::string> paths = o.files.empty() ? std::vector<std::string>{"-"} : o.files;
  paths.insert(paths.end(), o.overlays.begin(), o.overlays.end());
  std::vector<Input> inputs;
  for (const std::string& path : paths) {
    if (path == "-" && std::count(paths.begin(), paths.end(), "-") > 1) fail("stdin ('-') given twice");
    inputs.push_back({table::read_path(path), display_label(path)});
  }
  const std::string script = build_script(spec, inputs);

  if (!o.script.empty()) {
    std::ofstream file(o.script, std::ios::binary);
    if (!file) fail("--script {}: cannot open: {}", printable_name(o.script), std::strerror(errno));
    file << script;
    file.close();
    if (!file) fail("--script {}: write failed", printable_name(o.script));
  }
  if (!plot) return;
  // Fail here, not in gnuplot, which would carry on and write the image to stdout.
  if (!o.output.empty() && !std::ofstream(o.output, std::ios::binary | std::ios::app)) {
    fail("-o {}: cannot open: {}", printable_name(o.output), std::strerror(errno));
  }
  std::vector<std::string> argv{program, "-d"};
  if (spec.output.kind == Output::Kind::window) argv.emplace_back("-persist");
  Child gnuplot(argv, false);
  gnuplot.feed(script);
  const int status = gnuplot.wait();
  if (status != 0) fail("gnuplot failed (exit status {})", status);
}

}  // namespace mcg::plot
