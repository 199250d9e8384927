// farm.cpp: `hbil farm plan|run|check|slurm`: a shot cut into chunks for a render farm
// (pipeline/farm.h), each chunk run as one task, the check that the shot is complete, and the
// Slurm job array that runs it all.
#include "pipeline/farm.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli/commands.h"
#include "hbil/error.h"
#include "io/exr_output.h"
#include "io/sequence.h"

namespace hbil::cli {

namespace {

namespace fs = std::filesystem;

struct FarmOptions {
  pipeline::FarmRequest request;
  std::string plan, output, hbil, log_dir, job_name, sbatch_script;
  std::vector<std::string> sbatch;
  int chunk = -1, threads = 0, cpus = 2, memory_mb = 0;
  bool submit = false, quiet = false;
};

pipeline::FarmPlan load_plan(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(Exit::input, path + ": cannot read the farm plan");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(Exit::input, path + ": not JSON (" + std::string(e.what()) + ")");
  }
  return pipeline::farm_plan_from_json(j, path);
}

// Relative paths in a plan start from its directory: the commands that read one work there.
class InPlanDirectory {
 public:
  explicit InPlanDirectory(const pipeline::FarmPlan& plan) : back_(fs::current_path()) {
    std::error_code ec;
    fs::current_path(plan.directory, ec);
    if (ec)
      throw Error(Exit::input, "the plan's directory " + plan.directory + ": " + ec.message());
  }
  ~InPlanDirectory() {
    std::error_code ec;
    fs::current_path(back_, ec);
  }

 private:
  fs::path back_;
};

std::string absolute(const std::string& path) {
  return fs::absolute(path).lexically_normal();
}

void plan(const FarmOptions& o) {
  const RunRequest run = read_run_request(o.request.shot, o.request.run, "farm plan: run options");
  if (run.output.output.empty()) throw Error(Exit::usage, "farm plan: the run options need -o");
  const pipeline::FarmPlan p = pipeline::make_farm_plan(o.request, run.params);
  io::write_file(o.plan, to_json(p).dump(2) + "\n");
  if (o.quiet) return;
  std::printf("%s: %zu chunk%s of %s (%dx%d), pre-roll %d (%s), %d MB a task\n", o.plan.c_str(),
              p.chunks.size(), p.chunks.size() == 1 ? "" : "s", p.shot.c_str(), p.width, p.height,
              p.preroll, p.preroll_why.c_str(), p.memory_mb);
  for (size_t i = 0; i < p.chunks.size(); ++i) {
    const pipeline::FarmChunk& c = p.chunks[i];
    std::printf("  chunk %zu: frames %s, pre-roll %d (%s)\n", i,
                io::format_frame_list(c.frames).c_str(), c.preroll, c.starts.c_str());
  }
}

void run_chunk(const FarmOptions& o) {
  const pipeline::FarmPlan p = load_plan(o.plan);
  if (o.chunk < 0 || size_t(o.chunk) >= p.chunks.size())
    throw Error(Exit::usage, "--chunk " + std::to_string(o.chunk) + ": the plan has chunks 0-" +
                                 std::to_string(p.chunks.size() - 1));
  const std::string log = o.log_dir.empty() ? "" : absolute(o.log_dir);
  const InPlanDirectory here(p);
  run_command(p.shot, pipeline::chunk_run_args(p, size_t(o.chunk), o.threads, log),
              "farm run: the plan's run options");
}

void check(const FarmOptions& o) {
  const pipeline::FarmPlan p = load_plan(o.plan);
  const InPlanDirectory here(p);
  const RunRequest run = read_run_request(p.shot, p.run, o.plan + ": run options");
  std::vector<size_t> incomplete;
  size_t frames = 0, missing = 0;
  for (size_t i = 0; i < p.chunks.size(); ++i) {
    const pipeline::ChunkState st = pipeline::check_chunk(p, i, run.params, run.output);
    frames += p.chunks[i].frames.size();
    missing += st.missing.size();
    if (st.missing.empty()) continue;
    incomplete.push_back(i);
    std::printf("chunk %zu (frames %s): %zu frame%s not done, the first: %s\n", i,
                io::format_frame_list(p.chunks[i].frames).c_str(), st.missing.size(),
                st.missing.size() == 1 ? "" : "s", st.why.c_str());
  }
  if (incomplete.empty()) {
    std::printf("%s: complete: %zu frames in %zu chunks\n", o.plan.c_str(), frames,
                p.chunks.size());
    return;
  }
  std::string list;
  for (size_t i : incomplete) list += (list.empty() ? "" : ",") + std::to_string(i);
  std::printf("%s: incomplete: %zu of %zu frames not done, in chunk%s %s\n", o.plan.c_str(),
              missing, frames, incomplete.size() == 1 ? "" : "s", list.c_str());
  if (!o.sbatch_script.empty())
    std::printf("submit again: sbatch --array=%s %s\n", list.c_str(), o.sbatch_script.c_str());
  else
    std::printf("run again: hbil farm run %s --chunk N, for N in %s\n", o.plan.c_str(),
                list.c_str());
  throw Error(Exit::incomplete, o.plan + ": " + std::to_string(missing) + " frame" +
                                    (missing == 1 ? "" : "s") + " not done");
}

// Runs a command and returns what it printed (its first line), or throws Error(Exit::output).
std::string run_and_read(const std::string& command) {
  FILE* f = popen(command.c_str(), "r");
  if (!f) throw Error(Exit::output, "cannot run " + command);
  char line[512] = {};
  const bool got = std::fgets(line, sizeof line, f) != nullptr;
  const int status = pclose(f);
  std::string out = got ? line : "";
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  if (status != 0 || out.empty())
    throw Error(Exit::output, command + " failed (status " + std::to_string(status) + ")");
  return out;
}

void slurm(const FarmOptions& o) {
  const pipeline::FarmPlan p = load_plan(o.plan);
  pipeline::SlurmSettings s;
  s.plan_path = absolute(o.plan);
  std::error_code ec;
  s.hbil = o.hbil.empty() ? fs::read_symlink("/proc/self/exe", ec).string() : o.hbil;
  const std::string script = absolute(o.output);
  s.log_dir =
      o.log_dir.empty() ? (fs::path(script).parent_path() / "logs").string() : absolute(o.log_dir);
  s.cpus = o.cpus;
  s.memory_mb = o.memory_mb;
  s.sbatch = o.sbatch;
  s.job_name = o.job_name;
  const std::string check_script =
      (fs::path(script).parent_path() / (fs::path(script).stem().string() + ".check.sbatch"))
          .string();
  fs::create_directories(s.log_dir, ec);
  if (ec) throw Error(Exit::output, s.log_dir + ": cannot create folder: " + ec.message());
  io::write_file(script, pipeline::slurm_array_script(p, s));
  io::write_file(check_script, pipeline::slurm_check_script(p, s, script));
  for (const std::string& f : {script, check_script})
    fs::permissions(f, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add, ec);
  if (!o.quiet)
    std::printf("%s: %zu array tasks; %s: the check after them; logs in %s\n", script.c_str(),
                p.chunks.size(), check_script.c_str(), s.log_dir.c_str());
  if (!o.submit) return;
  const std::string array_id = run_and_read("sbatch --parsable " + script);
  const std::string check_id = run_and_read(
      "sbatch --parsable --dependency=afterany:" + array_id.substr(0, array_id.find(';')) + " " +
      check_script);
  std::printf("submitted: job array %s, check %s\n", array_id.c_str(), check_id.c_str());
}

}  // namespace

void add_farm(CLI::App& app) {
  auto o = std::make_shared<FarmOptions>();
  CLI::App* farm = app.add_subcommand(
      "farm", "a shot in chunks for a render farm: plan, run a chunk, check, Slurm job array");
  farm->require_subcommand(1);

  CLI::App* p = farm->add_subcommand("plan", "cut a shot into chunks, at its cuts, with pre-roll");
  p->add_option("SHOT", o->request.shot, "input EXR frame pattern, as for run")->required();
  p->add_option("RUN_OPTIONS", o->request.run,
                "after --: the options of hbil run for every chunk (-o is needed; not --frames, "
                "--preroll, --cut-frames, --threads, --skip-existing, --log-json)");
  p->add_option("-o,--output", o->plan, "the plan, JSON")->required();
  p->add_option("--frames", o->request.frames, "frames of the shot (default: every frame found)");
  p->add_option("--cut-frames", o->request.cut_frames,
                "frames that start a new shot (cuts are also found from the camera)");
  p->add_option("--chunk", o->request.chunk_size, "frames per chunk")
      ->default_val(50)
      ->check(count_check("a positive number of frames", 1));
  p->add_option("--preroll", o->request.preroll,
                "frames computed before a chunk that does not start at a cut: auto (the seam "
                "under 1e-3 from the preset's temporal memory) or a count")
      ->default_val("auto");
  p->add_flag("-q,--quiet", o->quiet, "print nothing");
  p->callback([o] { plan(*o); });

  CLI::App* r = farm->add_subcommand("run", "run one chunk of a plan (what a farm task does)");
  r->add_option("PLAN", o->plan, "the plan, JSON")->required();
  r->add_option("--chunk", o->chunk, "the chunk, from 0")->required();
  r->add_option("--threads", o->threads, "worker threads (0 = all cores)")
      ->default_val(0)
      ->check(count_check(kThreadsMeaning));
  r->add_option("--log-json", o->log_dir, "append the run's JSON lines to this file");
  r->callback([o] { run_chunk(*o); });

  CLI::App* c = farm->add_subcommand(
      "check", "whether every frame of a plan is in place, complete and made by its chunk");
  c->add_option("PLAN", o->plan, "the plan, JSON")->required();
  c->add_option("--sbatch", o->sbatch_script, "the job array script, named in the advice");
  c->callback([o] { check(*o); });

  CLI::App* s = farm->add_subcommand("slurm", "write a Slurm job array for a plan, and its check");
  s->add_option("PLAN", o->plan, "the plan, JSON")->required();
  s->add_option("-o,--output", o->output,
                "the job array script (the check goes beside it as NAME.check.sbatch)")
      ->required();
  s->add_option("--cpus-per-task", o->cpus, "cores per task, given to run as --threads")
      ->default_val(2)
      ->check(count_check("a positive count", 1));
  s->add_option("--mem", o->memory_mb, "MB per task (default: the plan's, from measured peaks)")
      ->check(count_check("a positive count of MB", 1));
  s->add_option("--logs", o->log_dir, "folder of the task logs (default: logs/ beside the script)");
  s->add_option("--hbil", o->hbil, "the hbil binary the tasks run (default: this one)");
  s->add_option("--job-name", o->job_name, "Slurm job name (default: hbil-<shot folder>)");
  s->add_option("--sbatch-option", o->sbatch,
                "one more #SBATCH line, e.g. --sbatch-option=--partition=post (repeatable)");
  s->add_flag("--submit", o->submit, "submit both with sbatch, the check after the array");
  s->add_flag("-q,--quiet", o->quiet, "print nothing but the submitted job ids");
  s->callback([o] { slurm(*o); });
}

}  // namespace hbil::cli
