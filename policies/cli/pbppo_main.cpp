// pbppo: the project's command-line tool.
#include <CLI/CLI.hpp>

#include "policies/cli/curves.hpp"
#include "policies/cli/eval.hpp"
#include "policies/cli/import_onnx.hpp"
#include "policies/cli/inspect.hpp"
#include "policies/cli/replay.hpp"
#include "policies/cli/sign.hpp"
#include "policies/cli/sweep.hpp"
#include "policies/cli/train.hpp"
#include "runtime/core/cli_checks.hpp"

int main(int argc, char** argv) {
  CLI::App app{"pbppo: train Pb-PPO policies and work with frozen policy blobs"};
  app.require_subcommand(1);

  std::string inspect_path;
  bool inspect_json = false;
  auto* inspect = app.add_subcommand("inspect", "Show everything in a policy blob's header");
  inspect->add_option("blob", inspect_path, "Policy blob file")->required();
  inspect->add_flag("--json", inspect_json, "Print JSON instead of text");
  bool inspect_weights = false;
  inspect->add_flag("--weights", inspect_weights, "With --json: every layer's weight (row-major [out][in]) and bias")
      ->needs("--json");

  pbppo::cli::SynthOptions synth_opts;
  auto* synth = app.add_subcommand("synth", "Write a random-weight blob of a given shape, with golden vectors");
  synth->add_option("--widths", synth_opts.widths, "Layer widths, input first, e.g. 48-512-256-128-12");
  synth->add_option("--activation", synth_opts.activation,
                    "Hidden activation: identity, tanh, elu, relu, leaky_relu (alpha 0.01)");
  synth->add_option("--seed", synth_opts.seed, "Seed for the weights")->check(pbppo::cli_checks::NonNegativeInteger());
  synth->add_option("--golden-rows", synth_opts.golden_rows, "Golden vector rows")->check(CLI::Range(1, 100000));
  synth->add_option("--out", synth_opts.out, "Output blob path")->required();
  synth->add_option("--layout", synth_opts.layout,
                    "A robot's IO layout (io_layout.yaml): the blob takes its observations and gives its actions");

  pbppo::trainer::TrainOptions train_opts;
  bool train_quiet = false;
  std::string train_resume;
  auto* train = app.add_subcommand("train", "Train a policy with PPO and a clip schedule (Pb-PPO)");
  pbppo::cli::AddTrainOptions(*train, train_opts, train_quiet, &train_resume);

  pbppo::cli::SweepOptions sweep_opts;
  auto* sweep = pbppo::cli::AddSweep(app, sweep_opts);

  pbppo::cli::EvalOptions eval_opts;
  auto* eval = app.add_subcommand("eval", "Run a policy blob on an environment with the runtime forward");
  pbppo::cli::AddEvalOptions(*eval, eval_opts);

  pbppo::cli::CurvesOptions curves_opts;
  auto* curves = app.add_subcommand(
      "curves", "Draw groups of training runs against each other: per group the mean of a log.csv column and a band");
  pbppo::cli::AddCurvesOptions(*curves, curves_opts);

  pbppo::cli::ReplayOptions replay_opts;
  auto* replay = pbppo::cli::AddReplay(app, replay_opts);

  pbppo::cli::ImportOnnxOptions import_opts;
  auto* import_onnx = pbppo::cli::AddImportOnnx(app, import_opts);

  pbppo::cli::SignOptions sign_opts;
  auto* sign = pbppo::cli::AddSign(app, sign_opts);
  pbppo::cli::VerifyOptions verify_opts;
  auto* verify = pbppo::cli::AddVerify(app, verify_opts);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // usage errors exit 2, after CLI11 printed the reason
  }
  if (*inspect) return pbppo::cli::Inspect(inspect_path, inspect_json, inspect_weights);
  if (*synth) return pbppo::cli::Synth(synth_opts);
  if (*train) {
    // The arguments after `train`, as given.
    std::vector<std::string> args;
    int k = 1;
    while (k < argc && std::string(argv[k]) != "train") ++k;
    for (++k; k < argc; ++k) args.emplace_back(argv[k]);
    return pbppo::cli::Train(train_opts, train_quiet, train_resume, args);
  }
  if (*sweep) return pbppo::cli::Sweep(sweep_opts);
  if (*eval) return pbppo::cli::Eval(eval_opts);
  if (*curves) return pbppo::cli::Curves(curves_opts);
  if (*replay) return pbppo::cli::Replay(replay_opts);
  if (*import_onnx) return pbppo::cli::ImportOnnx(import_opts);
  if (*sign) return pbppo::cli::Sign(sign_opts);
  if (*verify) return pbppo::cli::Verify(verify_opts);
  return 2;
}
