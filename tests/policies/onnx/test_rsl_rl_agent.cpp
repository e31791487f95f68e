// rsl_rl's agent.yaml (policies/onnx/rsl_rl_agent.hpp): the three generations of the file read
// into the actor they describe, bad files refused naming the field, and the graph's actor
// checked against it (memory, hidden layers, activation, normaliser), each disagreement named.
#include <doctest/doctest.h>

#include <string>

#include "policies/onnx/rsl_rl_agent.hpp"
#include "tests/support/text_edit.hpp"

namespace ox = pbppo::onnx;
using pbppo::policy::Activation;
using pbppo::policy::LayerKind;

namespace {

// As Isaac Lab dumps an rsl_rl 2.3 runner configuration (abridged: the algorithm's fields are
// training's only).
const char* kPolicy = R"(seed: 42
device: cuda:0
num_steps_per_env: 24
max_iterations: 1500
empirical_normalization: false
obs_groups: {policy: [policy], critic: [policy]}
clip_actions: null
save_interval: 50
experiment_name: quadruped_flat
policy:
  class_name: ActorCritic
  init_noise_std: 1.0
  noise_std_type: scalar
  actor_obs_normalization: false
  critic_obs_normalization: false
  actor_hidden_dims: [128, 64, 32]
  critic_hidden_dims: [512, 256, 128]
  activation: elu
algorithm:
  class_name: PPO
  clip_param: 0.2
)";

// rsl_rl 4: the actor as a model of its own; the deprecated policy section left unset.
const char* kActor = R"(seed: 42
empirical_normalization: ???
clip_actions: 5.0
policy: ???
actor:
  class_name: RNNModel
  hidden_dims: [64]
  activation: elu
  obs_normalization: true
  rnn_type: GRU
  rnn_hidden_dim: 32
  rnn_num_layers: 2
  distribution_cfg: {class_name: GaussianDistribution, init_std: 1.0, std_type: scalar}
critic:
  class_name: MLPModel
  hidden_dims: [256, 256]
  activation: elu
)";

ox::AgentFile Parse(const std::string& text) {
  auto a = ox::ParseAgentFile(text, "agent.yaml");
  REQUIRE_MESSAGE(a.ok(), a.error().message);
  return std::move(*a);
}

std::string Refusal(const std::string& text) {
  auto a = ox::ParseAgentFile(text, "agent.yaml");
  REQUIRE_FALSE(a.ok());
  return a.error().message;
}

std::string CheckRefusal(const ox::AgentFile& a, const pbppo::policy::PolicySpec& s, bool normalises) {
  auto r = ox::CheckActor(a, s, normalises);
  REQUIRE_FALSE(r.ok());
  return r.error().message;
}

}  // namespace

TEST_CASE("rsl_rl agent.yaml: the policy section, the actor model and the oldest runner flag are read") {
  const ox::AgentFile p = Parse(kPolicy);
  CHECK(p.section == "policy");
  CHECK(p.class_name == "ActorCritic");
  CHECK(p.hidden_dims == std::vector<std::uint32_t>{128, 64, 32});
  CHECK(p.activation == "elu");
  CHECK(p.normaliser_field.empty());
  CHECK(p.rnn_type.empty());
  CHECK(p.clip_actions == 0.0);
  const ox::AgentFile a = Parse(kActor);
  CHECK(a.section == "actor");
  CHECK(a.hidden_dims == std::vector<std::uint32_t>{64});
  CHECK(a.normaliser_field == "actor.obs_normalization");
  CHECK(a.rnn_type == "gru");
  CHECK(a.rnn_hidden_dim == 32);
  CHECK(a.rnn_num_layers == 2);
  CHECK(a.clip_actions == 5.0);
  using pbppo::test::ReplaceOnce;
  // Before rsl_rl 2.3 the runner's empirical_normalization asked for it.
  const std::string old =
      ReplaceOnce(ReplaceOnce(kPolicy, "empirical_normalization: false", "empirical_normalization: true"),
                  "  actor_obs_normalization: false\n", "");
  CHECK(Parse(old).normaliser_field == "empirical_normalization");
}

TEST_CASE("rsl_rl agent.yaml: bad files refused naming the field") {
  using pbppo::test::ReplaceOnce;
  const std::string p = kPolicy, a = kActor;
  CHECK(Refusal(ReplaceOnce(p, "policy:\n", "learner:\n")) ==
        "agent.yaml: top level: neither actor (rsl_rl 4) nor policy (earlier): no actor described");
  CHECK(Refusal(ReplaceOnce(p, "[128, 64, 32]", "[128, 64.5, 32]")) ==
        "agent.yaml: policy.actor_hidden_dims[1]: 64.5 is not a whole number");
  CHECK(Refusal(ReplaceOnce(p, "[128, 64, 32]", "128")) ==
        "agent.yaml: policy.actor_hidden_dims: '128' is not a list of widths");
  CHECK(Refusal(ReplaceOnce(p, "[128, 64, 32]", "[128, 0, 32]")).find("policy.actor_hidden_dims[1]: ") !=
        std::string::npos);
  CHECK(Refusal(ReplaceOnce(a, "rnn_type: GRU", "rnn_type: transformer")) ==
        "agent.yaml: actor.rnn_type: 'transformer' is not lstm or gru");
  CHECK(
      Refusal(ReplaceOnce(a, "  rnn_hidden_dim: 32\n", "")).find("agent.yaml: actor: missing field 'rnn_hidden_dim'") ==
      0);
  CHECK(Refusal(ReplaceOnce(p, "class_name: ActorCritic\n", "class_name: ActorCriticRecurrent\n")) ==
        "agent.yaml: policy.rnn_type: missing: class ActorCriticRecurrent is recurrent");
  CHECK(Refusal(ReplaceOnce(p, "clip_actions: null", "clip_actions: -1")).find("agent.yaml: clip_actions: ") == 0);
  CHECK(Refusal(ReplaceOnce(p, "actor_obs_normalization: false", "actor_obs_normalization: maybe"))
            .find("agent.yaml: policy.actor_obs_normalization") == 0);
  CHECK(Refusal(ReplaceOnce(p, "  activation: elu\n", "  activation: [elu]\n")) ==
        "agent.yaml: policy.activation: '[elu]' is not a name");
  CHECK(Refusal(p + "policy: {}\n").find("key 'policy' given twice") != std::string::npos);
  CHECK(Refusal("[1, 2]\n") == "agent.yaml: top level: not a map of fields (rsl_rl's agent.yaml)");
}

TEST_CASE("rsl_rl agent.yaml: the graph's actor checked against it - memory, hidden layers, activation, normaliser") {
  using pbppo::policy::MakeRandomRecurrentSpec;
  using pbppo::policy::MakeRandomSpec;
  const ox::AgentFile p = Parse(kPolicy);
  const auto mlp = MakeRandomSpec({51, 128, 64, 32, 12}, Activation::kElu, 1);
  auto notes = ox::CheckActor(p, mlp, false);
  REQUIRE_MESSAGE(notes.ok(), notes.error().message);
  CHECK(notes->size() == 1);
  CHECK(notes->front() == "agent.yaml:  hidden layers [128, 64, 32] elu: the graph's");
  CHECK(CheckRefusal(p, MakeRandomSpec({51, 256, 128, 12}, Activation::kElu, 1), false) ==
        "agent.yaml: policy.actor_hidden_dims: [128, 64, 32], but the graph's actor has hidden layers [256, 128]: "
        "the agent.yaml of another run?");
  CHECK(CheckRefusal(p, MakeRandomSpec({51, 128, 64, 32, 12}, Activation::kTanh, 1), false) ==
        "agent.yaml: policy.activation: 'elu', but the graph's hidden layers use tanh");
  // Trained with a normaliser the export left out.
  ox::AgentFile normalised = p;
  normalised.normaliser_field = "policy.actor_obs_normalization";
  CHECK(CheckRefusal(normalised, mlp, false)
            .find("agent.yaml: policy.actor_obs_normalization: true: the policy was "
                  "trained on normalised observations, but the graph holds no "
                  "normaliser") == 0);
  auto with = ox::CheckActor(normalised, mlp, true);
  REQUIRE(with.ok());
  CHECK(with->back() == "agent.yaml:  policy.actor_obs_normalization: the graph's normaliser");
  // A recurrent graph against a feed-forward file, and the other way round.
  const auto lstm = MakeRandomRecurrentSpec({51, 64, 32, 12}, Activation::kElu, 0, LayerKind::kLstm, false, 2);
  CHECK(CheckRefusal(p, lstm, false) ==
        "agent.yaml: policy.class_name: 'ActorCritic': a feed-forward actor, but the graph's starts with 1 lstm "
        "layer(s): the agent.yaml of another run?");
  const ox::AgentFile a = Parse(kActor);  // gru 32 x 2, then [64], elu, normalised
  CHECK(CheckRefusal(a, mlp, true) ==
        "agent.yaml: actor.rnn_type: 'gru', but the graph's actor has no recurrent layer (an MLP): the agent.yaml of "
        "another run, or an export of the MLP alone?");
  CHECK(CheckRefusal(a, lstm, true) == "agent.yaml: actor.rnn_type: 'gru', but the graph's recurrent layers are lstm");
  const auto gru1 = MakeRandomRecurrentSpec({51, 32, 64, 12}, Activation::kElu, 0, LayerKind::kGru, true, 3);
  CHECK(CheckRefusal(a, gru1, true) == "agent.yaml: actor.rnn_num_layers: 2, but the graph's actor has 1 gru layer(s)");
  // Two GRU layers of 32 then the MLP [64]: the file's actor.
  auto gru2 = MakeRandomRecurrentSpec({51, 32, 32, 64, 12}, Activation::kElu, 0, LayerKind::kGru, true, 4);
  gru2.layers[1] = MakeRandomRecurrentSpec({32, 32, 64, 12}, Activation::kElu, 0, LayerKind::kGru, true, 5).layers[0];
  auto ok = ox::CheckActor(a, gru2, true);
  REQUIRE_MESSAGE(ok.ok(), ok.error().message);
  CHECK(ok->front() == "agent.yaml:  gru 32 x 2: the graph's memory");
  ox::AgentFile wide = a;
  wide.rnn_hidden_dim = 48;
  CHECK(CheckRefusal(wide, gru2, true) == "agent.yaml: actor.rnn_hidden_dim: 48, but the graph's gru layer 0 holds 32");
}
