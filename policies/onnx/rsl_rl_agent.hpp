// rsl_rl's runner settings as Isaac Lab writes them beside a trained policy (logs/.../params/
// agent.yaml, next to env.yaml and, from unitree_rl_lab, deploy.yaml): what they say about the
// deployed actor, read to check the ONNX file against the run that trained it and to apply the
// one setting that acts outside the network (clip_actions, which Isaac Lab's environment wrapper
// applies to the raw actions before the action term). Every other field (the algorithm, the
// critic, the logger) is training's only and is not read. Set-up time only (pbppo import-onnx).
//
// The three generations of the file are read: rsl_rl >= 4 (actor: {class_name MLPModel |
// RNNModel, hidden_dims, activation, obs_normalization, rnn_type, rnn_hidden_dim,
// rnn_num_layers}), 2.3-3 (policy: {class_name ActorCritic | ActorCriticRecurrent,
// actor_hidden_dims, activation, actor_obs_normalization, rnn_*}) and earlier (the same policy
// section with the top level's empirical_normalization).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::onnx {

struct AgentFile {
  std::string origin;
  std::string section;                     // "actor" or "policy": where the actor's fields are
  std::string class_name;                  // as written; "" when not given
  std::vector<std::uint32_t> hidden_dims;  // the MLP's hidden widths; empty when not given
  std::string activation;                  // rsl_rl's name; "" when not given
  std::string normaliser_field;            // the field that asks for observation normalisation; "" none
  std::string rnn_type;                    // "lstm" or "gru"; "" for a feed-forward actor
  std::uint32_t rnn_hidden_dim = 0;        // when rnn_type is given
  std::uint32_t rnn_num_layers = 0;        // when rnn_type is given
  double clip_actions = 0;                 // |raw action| bound before the action term; 0: none
};

Result<AgentFile> ParseAgentFile(const std::string& text, const std::string& origin);
Result<AgentFile> ReadAgentFile(const std::string& path);
// The agent.yaml in the same folder as `deploy_path`, or "" when there is none.
std::string AgentFileBeside(const std::string& deploy_path);

// The imported actor (`spec`; `graph_normalises`: the graph held an observation normaliser)
// against what the file says was trained: the first disagreement refused naming the field and
// both sides (an agent.yaml of another run, or an export that left the normaliser out), else what
// was checked, one line each.
Result<std::vector<std::string>> CheckActor(const AgentFile& agent, const policy::PolicySpec& spec,
                                            bool graph_normalises);

}  // namespace pbppo::onnx
