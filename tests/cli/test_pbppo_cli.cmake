# pbppo synth / inspect on real files, including the bad inputs.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

function(run expect_rc)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL expect_rc)
    message(FATAL_ERROR "'${ARGN}' exited ${rc}, expected ${expect_rc}\nstdout: ${out}\nstderr: ${err}")
  endif()
  set(OUT "${out}" PARENT_SCOPE)
  set(ERR "${err}" PARENT_SCOPE)
endfunction()

# Fails with `why` unless files a and b hold the same bytes.
function(expect_same_bytes a b why)
  file(SHA256 ${a} ha)
  file(SHA256 ${b} hb)
  if(NOT ha STREQUAL hb)
    message(FATAL_ERROR "${why}: ${a} and ${b} differ")
  endif()
endfunction()

# Fails unless the JSON file's value at `key` is `want` (compared as text).
function(expect_json file key want)
  file(READ ${file} json)
  string(JSON got GET "${json}" ${key})
  if(NOT got STREQUAL want)
    message(FATAL_ERROR "${file}: ${key} is '${got}', expected '${want}'")
  endif()
endfunction()

function(expect_in haystack needle)
  string(FIND "${haystack}" "${needle}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "expected to find '${needle}' in:\n${haystack}")
  endif()
endfunction()

# expect_choice(SCRIPT DIR N HEADER): a selection script's output in DIR: select.csv with HEADER and one
# row for each of N candidates, and the chosen selected.blob, with its .golden, a valid blob.
function(expect_choice script dir n header)
  file(STRINGS ${dir}/select.csv rows)
  list(LENGTH rows lines)
  math(EXPR want "${n} + 1")
  if(NOT lines EQUAL want)
    message(FATAL_ERROR "select.csv: ${lines} lines for ${n} candidates:\n${rows}")
  endif()
  expect_in("${rows}" "${header}")
  if(NOT EXISTS ${dir}/selected.blob OR NOT EXISTS ${dir}/selected.golden)
    message(FATAL_ERROR "${script} wrote no selected.blob and .golden")
  endif()
  run(0 ${PBPPO} inspect ${dir}/selected.blob)
endfunction()

run(0 ${PBPPO} synth --widths 24-64-64-2 --activation tanh --seed 4 --out ${WORK}/p3.blob)
if(NOT EXISTS ${WORK}/p3.golden)
  message(FATAL_ERROR "synth wrote no golden file")
endif()
run(0 ${PBPPO} inspect ${WORK}/p3.blob)
expect_in("${OUT}" "24 -> 64 tanh -> 64 tanh -> 2 identity")
expect_in("${OUT}" "parameters  5890")
expect_in("${OUT}" "crc32 0x")
run(0 ${PBPPO} inspect --json ${WORK}/p3.blob)
expect_in("${OUT}" "\"input_size\": 24")
expect_in("${OUT}" "\"activation\": \"tanh\"")
string(JSON n GET "${OUT}" parameter_count)
if(NOT n EQUAL 5890)
  message(FATAL_ERROR "parameter_count ${n}")
endif()
string(JSON none ERROR_VARIABLE no_weight GET "${OUT}" layers 0 weight)
if(no_weight STREQUAL "NOTFOUND")
  message(FATAL_ERROR "inspect --json without --weights printed the weights")
endif()
# --weights: each layer's weight (row-major [out][in]) and bias.
run(0 ${PBPPO} inspect --json --weights ${WORK}/p3.blob)
string(JSON nw LENGTH "${OUT}" layers 0 weight)
string(JSON nb LENGTH "${OUT}" layers 2 bias)
if(NOT nw EQUAL 1536 OR NOT nb EQUAL 2)
  message(FATAL_ERROR "inspect --json --weights: layer 0 has ${nw} weights (1536), layer 2 ${nb} biases (2)")
endif()
run(2 ${PBPPO} inspect --weights ${WORK}/p3.blob)
expect_in("${ERR}" "--weights requires --json")

# leaky_relu: synth gives hidden layers alpha 0.01; inspect shows it (JSON: only on those layers).
run(0 ${PBPPO} synth --widths 6-16-8-3 --activation leaky_relu --seed 2 --out ${WORK}/leaky.blob)
run(0 ${PBPPO} inspect ${WORK}/leaky.blob)
expect_in("${OUT}" "6 -> 16 leaky_relu(alpha=0.01) -> 8 leaky_relu(alpha=0.01) -> 3 identity")
run(0 ${PBPPO} inspect --json ${WORK}/leaky.blob)
string(JSON act GET "${OUT}" layers 0 activation)
string(JSON alpha GET "${OUT}" layers 1 alpha)
string(JSON none ERROR_VARIABLE no_alpha GET "${OUT}" layers 2 alpha)
if(NOT act STREQUAL "leaky_relu" OR NOT alpha MATCHES "^0\\.0099999" OR no_alpha STREQUAL "NOTFOUND")
  message(FATAL_ERROR "inspect --json of a leaky_relu blob: activation '${act}', alpha '${alpha}', "
                      "identity layer's alpha '${none}' (${no_alpha})")
endif()
run(2 ${PBPPO} train --activation leaky_relu --out ${WORK}/bad)
expect_in("${ERR}" "--activation: 'leaky_relu' is not trainable here")

# The shipped P3 blob: synth with the same seed reproduces it byte for byte.
run(0 ${PBPPO} synth --widths 24-64-64-2 --activation tanh --seed 3 --out ${WORK}/again.blob)
expect_same_bytes(${WORK}/again.blob ${SOURCE_DIR}/tests/data/blobs/p3.blob
                  "synth is not deterministic or the shipped p3.blob drifted")

# Bad inputs.
file(WRITE ${WORK}/junk.blob "not a blob at all, definitely not a blob, this text is longer than a header")
run(1 ${PBPPO} inspect ${WORK}/junk.blob)
expect_in("${ERR}" "junk.blob: policy blob: magic: not a pbppo policy blob")
run(1 ${PBPPO} inspect ${WORK}/missing.blob)
expect_in("${ERR}" "missing.blob: cannot open")
run(2 ${PBPPO} synth --widths 24-x-2 --out ${WORK}/bad.blob)
expect_in("${ERR}" "--widths: 'x' is not a positive width")
run(2 ${PBPPO} synth --activation swish --out ${WORK}/bad.blob)
expect_in("${ERR}" "--activation 'swish' unknown")
run(1 ${PBPPO} synth --out ${WORK}/no/such/dir/p.blob)
expect_in("${ERR}" "cannot create")
run(2 ${PBPPO} inspect)
expect_in("${ERR}" "blob is required")
# synth for a robot's IO layout: its names, hash and action map; widths that do not fit are refused.
run(0 ${PBPPO} synth --layout ${SOURCE_DIR}/tests/data/diffbot/io_layout.yaml --widths 10-16-3 --activation tanh
    --out ${WORK}/diffbot.blob)
run(0 ${PBPPO} inspect ${WORK}/diffbot.blob)
expect_in("${OUT}" "last_action_head_pan")
expect_in("${OUT}" "range [-15, 15]")
run(2 ${PBPPO} synth --layout ${SOURCE_DIR}/tests/data/diffbot/io_layout.yaml --widths 12-16-3
    --out ${WORK}/bad.blob)
expect_in("${ERR}" "has 10 observations and 3 actions: the widths must start with 10 and end with 3")
run(2 ${PBPPO} synth --layout ${WORK}/none.yaml --widths 10-3 --out ${WORK}/bad.blob)
expect_in("${ERR}" "--layout: ${WORK}/none.yaml: cannot open")
run(2 ${PBPPO} frobnicate)

# pbppo train / eval on Pendulum, small budgets.
run(0 ${PBPPO} train --env pendulum --schedule pbppo --arms 0.05:0.4:3 --steps 4096 --envs 2 --rollout 512
    --epochs 2 --seed 1 --no-plots --quiet --out ${WORK}/run1)
foreach(f log.csv summary.json policy.blob policy.golden)
  if(NOT EXISTS ${WORK}/run1/${f})
    message(FATAL_ERROR "pbppo train wrote no ${f}")
  endif()
endforeach()
expect_in("${OUT}" "evaluation steps")
expect_json(${WORK}/run1/summary.json env_steps 4096)
run(0 ${PBPPO} inspect ${WORK}/run1/policy.blob)
expect_in("${OUT}" "pendulum")
run(0 ${PBPPO} eval ${WORK}/run1/policy.blob --env pendulum --episodes 3 --seed 7)
expect_in("${OUT}" "mean return")
expect_in("${OUT}" "steps 600")
# Same seed and thread count in two processes: byte-identical blobs.
foreach(k a b)
  run(0 ${PBPPO} train --schedule pbppo-reference --arms 0.1,0.2 --feedback rollout --steps 4096 --envs 4
      --rollout 256 --threads 2 --epochs 2 --normalize-obs --no-plots --quiet --out ${WORK}/det_${k})
endforeach()
expect_same_bytes(${WORK}/det_a/policy.blob ${WORK}/det_b/policy.blob
                  "two runs with the same seed and threads wrote different blobs")
run(0 ${PBPPO} train --schedule fixed:0.2 --steps 2048 --rollout 1024 --epochs 1 --no-plots --quiet --out ${WORK}/run2)
# --lr-schedule: the adaptive rule's rate in every log row, the schedule in the summary; bad ones refused.
run(0 ${PBPPO} train --schedule fixed:0.2 --lr-schedule adaptive:0.02 --steps 4096 --rollout 1024 --epochs 2
    --no-plots --quiet --out ${WORK}/adaptive)
expect_json(${WORK}/adaptive/summary.json lr_schedule "adaptive:0.02")
file(STRINGS ${WORK}/adaptive/log.csv rows)
list(GET rows 0 header)
expect_in("${header}" ",learning_rate,kl,")
list(LENGTH rows n)
if(NOT n EQUAL 5)
  message(FATAL_ERROR "log.csv: ${n} lines for 4 iterations")
endif()
# pbppo curves: groups of runs against each other (report/), bad groups refused.
run(0 ${PBPPO} curves --out ${WORK}/curves.png --title "two groups" "adaptive=${WORK}/adaptive,${WORK}/run2"
    "bandit=${WORK}/run1")
file(READ ${WORK}/curves.png magic LIMIT 4 HEX)
if(NOT magic STREQUAL "89504e47")
  message(FATAL_ERROR "pbppo curves wrote no PNG (${magic})")
endif()
run(2 ${PBPPO} curves --out ${WORK}/bad.png nogroup)
expect_in("${ERR}" "group 'nogroup' is not NAME=RUN_DIR[,RUN_DIR...]")
run(1 ${PBPPO} curves --out ${WORK}/bad.png --column nothing "a=${WORK}/run1")
expect_in("${ERR}" "log.csv has no column 'nothing'")
run(2 ${PBPPO} train --lr-schedule cosine --out ${WORK}/bad)
expect_in("${ERR}" "--lr-schedule: 'cosine' unknown (constant, anneal, adaptive or adaptive:KL)")
# A negative seed is refused, not wrapped around to 2^64 - 4.
run(2 ${PBPPO} train --seed -4 --out ${WORK}/bad)
expect_in("${ERR}" "--seed: '-4' is not an integer")
if(EXISTS ${WORK}/bad)
  message(FATAL_ERROR "a refused train wrote ${WORK}/bad")
endif()
run(2 ${PBPPO} train --lr-schedule adaptive:2 --out ${WORK}/bad)
expect_in("${ERR}" "--lr-schedule: 'adaptive:2': desired KL '2' is not a number in (0, 1]")
run(2 ${PBPPO} train --env pendulum --terrain mixed --out ${WORK}/bad)
expect_in("${ERR}" "--terrain: only quadruped-walk has terrains to choose, not 'pendulum'")
run(1 ${PBPPO} eval ${WORK}/p3.blob --env pendulum)
expect_in("${ERR}" "p3.blob")
run(2 ${PBPPO} train --env cartpole --out ${WORK}/bad)
expect_in("${ERR}" "env: 'cartpole' unknown")
run(2 ${PBPPO} train --arms 0.1:1.5:3 --out ${WORK}/bad)
expect_in("${ERR}" "--arms: clip bound 1.5 is outside [0, 1]")
run(2 ${PBPPO} train --schedule fixed:2 --out ${WORK}/bad)
expect_in("${ERR}" "clip bound 2 is outside [0, 1]")
run(2 ${PBPPO} train --schedule sometimes --out ${WORK}/bad)
expect_in("${ERR}" "'sometimes' unknown")
run(2 ${PBPPO} train --envs 0 --out ${WORK}/bad)
expect_in("${ERR}" "--envs: 0")
run(2 ${PBPPO} train --feedback never --out ${WORK}/bad)
expect_in("${ERR}" "--feedback: 'never' unknown")
run(2 ${PBPPO} train --hidden 64-x --out ${WORK}/bad)
expect_in("${ERR}" "--hidden: 'x'")
run(2 ${PBPPO} train --steps 1e5)
expect_in("${ERR}" "--out is required")
run(1 ${PBPPO} train --steps 2048 --rollout 1024 --out ${WORK}/run1/summary.json/x --quiet)
expect_in("${ERR}" "--out")

# Ctrl-C: a clean stop with the log, the summary and a checkpoint blob. The interrupt is delivered twice
# within a second, as `timeout -s INT` can (to the process, then to its group): that is still one Ctrl-C.
# (auv-nav with long rollouts, so that the second comes while the run is still finishing its iteration.)
file(WRITE ${WORK}/int.sh [=[
"$1" train --env auv-nav --envs 4 --rollout 4096 --steps 1e9 --no-plots --quiet --out "$2" 2> "$2.err" &
p=$!
while ! grep -q 'pbppo train:' "$2.err" 2> /dev/null; do sleep 0.1; done
sleep 1
kill -INT $p
sleep 0.1
kill -INT $p
wait $p
rc=$?
cat "$2.err" >&2
exit $rc
]=])
run(130 sh ${WORK}/int.sh ${PBPPO} ${WORK}/int)
expect_in("${ERR}" "interrupted")
expect_json(${WORK}/int/summary.json interrupted ON)
run(0 ${PBPPO} eval ${WORK}/int/policy.blob --env auv-nav --episodes 2)
# auv-nav: a tiny run, evaluation with the task's figures, the trajectory plot and CSV, bad inputs.
run(0 ${PBPPO} train --env auv-nav --layout medium --schedule pbppo --arms 0.1,0.3 --feedback rollout --steps 4096
    --envs 4 --rollout 512 --minibatch 256 --epochs 1 --snapshots 2 --no-plots --quiet --out ${WORK}/auv)
run(0 ${PBPPO} inspect ${WORK}/auv/policy.blob)
expect_in("${OUT}" "auv-nav:medium")
expect_in("${OUT}" "surge_speed")
run(0 ${PBPPO} eval ${WORK}/auv/policy.blob --env auv-nav --layout easy --episodes 2 --seed 5 --plot ${WORK}/auv.png
    --trajectories ${WORK}/auv.csv)
expect_in("${OUT}" "success ")
expect_in("${OUT}" "collisions ")
if(NOT EXISTS ${WORK}/auv.png OR NOT EXISTS ${WORK}/auv.csv)
  message(FATAL_ERROR "pbppo eval --plot/--trajectories wrote no file")
endif()
file(STRINGS ${WORK}/auv.csv lines LIMIT_COUNT 1)
expect_in("${lines}" "episode,step,t_s,x_m,y_m")
run(0 ${PBPPO} eval ${WORK}/auv/policy.blob --env auv-nav --layout hard --episodes 1 --json)
string(JSON sr GET "${OUT}" success_rate)
string(JSON col GET "${OUT}" collisions)
# --outcomes: one row per episode whose outcomes add up to the printed counts (mixed: each row names
# its layout; hard and medium episodes carry random obstacles).
run(0 ${PBPPO} eval ${WORK}/auv/policy.blob --env auv-nav --layout mixed --episodes 6 --seed 3 --json
    --outcomes ${WORK}/outcomes.csv)
string(JSON want_success GET "${OUT}" successes)
string(JSON want_collisions GET "${OUT}" collisions)
string(JSON want_timeouts GET "${OUT}" timeouts)
file(STRINGS ${WORK}/outcomes.csv rows)
list(LENGTH rows n)
if(NOT n EQUAL 7)
  message(FATAL_ERROR "--outcomes: ${n} lines for 6 episodes:\n${rows}")
endif()
list(POP_FRONT rows header)
expect_in("${header}" "episode,layout,outcome,targets,time_s,return,x_m,y_m,yaw_rad,clearance_m,nearest,random_obstacles")
set(got_success 0)
set(got_collision 0)
set(got_timeout 0)
set(episode 0)
foreach(row IN LISTS rows)
  if(NOT row MATCHES "^${episode},(easy|medium|hard),(success|collision|timeout),[0-3],[0-9.e+-]+,[0-9.e+-]+,[0-9.e+-]+,[0-9.e+-]+,[0-9.e+-]+,[0-9.e+-]+,(wall|layout|random),")
    message(FATAL_ERROR "--outcomes: bad row ${episode}: ${row}")
  endif()
  set(layout ${CMAKE_MATCH_1})
  math(EXPR got_${CMAKE_MATCH_2} "${got_${CMAKE_MATCH_2}} + 1")
  if(layout STREQUAL "hard" AND NOT row MATCHES "[ ,][0-9.e+-]+:[0-9.e+-]+:[0-9.e+-]+$")
    message(FATAL_ERROR "--outcomes: a hard episode without its random obstacles: ${row}")
  endif()
  math(EXPR episode "${episode} + 1")
endforeach()
if(NOT got_success EQUAL want_success OR NOT got_collision EQUAL want_collisions OR NOT got_timeout EQUAL want_timeouts)
  message(FATAL_ERROR "--outcomes: ${got_success}/${got_collision}/${got_timeout} rows, eval says "
                      "${want_success}/${want_collisions}/${want_timeouts}")
endif()
run(2 ${PBPPO} eval ${WORK}/auv/policy.blob --env auv-nav --episodes 1 --outcomes ${WORK}/no/such/dir/o.csv)
expect_in("${ERR}" "--outcomes: cannot write '${WORK}/no/such/dir/o.csv'")
run(2 ${PBPPO} eval ${WORK}/auv/policy.blob --env auv-nav --layout maze --episodes 1)
expect_in("${ERR}" "--layout: 'maze' unknown")
run(2 ${PBPPO} train --env auv-nav --layout maze --out ${WORK}/bad)
expect_in("${ERR}" "--layout: 'maze' unknown")
run(1 ${PBPPO} eval ${WORK}/auv/policy.blob --env pendulum --episodes 1)
expect_in("${ERR}" "does not fit robot layout")
run(2 ${PBPPO} eval ${WORK}/run1/policy.blob --env pendulum --episodes 1 --plot ${WORK}/x.png)
expect_in("${ERR}" "--plot: only auv-nav and quadruped-walk draw plots, not 'pendulum'")
run(2 ${PBPPO} eval ${WORK}/auv/policy.blob --env auv-nav --layout mixed --episodes 1 --plot ${WORK}/x.png)
expect_in("${ERR}" "not 'mixed'")

# tools/select_auv.sh: the run's two snapshots evaluated per layout, the choice copied with its
# golden vectors, one row per candidate; bad arguments refused.
set(select ${SOURCE_DIR}/tools/select_auv.sh)
run(0 env PBPPO=${PBPPO} EPISODES=2 bash ${select} ${WORK}/auv)
expect_in("${OUT}" "snapshots/000000002048.blob")
expect_in("${OUT}" "<- selected")
expect_in("${OUT}" "the choice on 2 other episodes per layout (seed 888): easy ")
expect_choice(select_auv ${WORK}/auv 2 "candidate,easy,easy_collisions,easy_timeouts,medium")
run(2 env PBPPO=${PBPPO} bash ${select} ${WORK}/no-such-run)
expect_in("${ERR}" "usage: tools/select_auv.sh RUN_DIR")
run(2 env PBPPO=${PBPPO} EPISODES=ten bash ${select} ${WORK}/auv)
expect_in("${ERR}" "EPISODES: 'ten' is not a positive integer")
run(2 env PBPPO=${PBPPO} CONFIRM_SEED=777 bash ${select} ${WORK}/auv)
expect_in("${ERR}" "CONFIRM_SEED must differ from DEV_SEED (777)")
run(2 env PBPPO=${PBPPO} bash ${select} ${WORK}/run1)
expect_in("${ERR}" "holds no best.blob and no snapshots/*.blob")

# quadruped-walk: a tiny run with the privileged critic, the paper's test on its blob, bad inputs.
run(0 ${PBPPO} train --env quadruped-walk --terrain mixed --schedule fixed:0.2 --steps 384 --envs 8 --rollout 24
    --minibatch 96 --epochs 1 --hidden 16-16 --activation elu --lr-schedule adaptive:0.01 --seed 1 --threads 2
    --no-plots --quiet --out ${WORK}/walk)
expect_json(${WORK}/walk/summary.json terrain mixed)
file(STRINGS ${WORK}/walk/log.csv header LIMIT_COUNT 1)
expect_in("${header}" "tracking_vx_100,tracking_vy_100,tracking_yaw_rate_100")
run(0 ${PBPPO} inspect ${WORK}/walk/policy.blob)
expect_in("${OUT}" "quadruped-walk")
expect_in("${OUT}" "45 -> 16 elu -> 16 elu -> 12 identity")
# The provenance records the terrain, the noise and the randomisation of the training.
expect_in("${OUT}" "quadruped-walk, robot quadruped, terrain mixed, commands every 5 s (1 heading, 0 zero planar); noise x1 (ang vel ")
expect_in("${OUT}" "; friction 0.5..1.25, mass -1..+1 kg, gains x0.9..1.1, latency 0..1, pushes 1 m/s/15 s")
run(0 ${PBPPO} eval ${WORK}/walk/policy.blob --env quadruped-walk --episodes 2 --seed 3 --json
    --plot ${WORK}/walk/eval.png)
string(JSON robots GET "${OUT}" robots)
string(JSON vx GET "${OUT}" mean_abs_error vx_mps)
if(NOT robots EQUAL 2 OR vx LESS_EQUAL 0)
  message(FATAL_ERROR "eval: robots ${robots}, vx error ${vx}")
endif()
if(NOT EXISTS ${WORK}/walk/eval.png)
  message(FATAL_ERROR "eval --plot wrote no PNG")
endif()
run(0 ${PBPPO} eval ${WORK}/walk/policy.blob --env quadruped-walk --terrain mixed --episodes 2)
expect_in("${OUT}" "mean |error|  vx")
expect_in("${OUT}" "falls ")
# tools/select_quadruped.sh: a run's last policy and its two snapshots walk the demo schedule in
# MuJoCo and take the paper's test; one row per candidate, the choice copied with its golden
# vectors (two iterations cannot walk: none qualifies, and the script says so); bad input refused.
run(0 ${PBPPO} train --env quadruped-walk --schedule fixed:0.2 --steps 384 --envs 8 --rollout 24 --minibatch 96
    --epochs 1 --hidden 16-16 --activation elu --seed 1 --threads 2 --no-plots --quiet --snapshots 2
    --out ${WORK}/walk_select)
set(select_q ${SOURCE_DIR}/tools/select_quadruped.sh)
run(0 env PBPPO=${PBPPO} FLAT_ROBOTS=2 MIXED_ROBOTS=2 DEMO_SEEDS=1 bash ${select_q} ${WORK}/walk_select)
expect_in("${OUT}" "snapshots/000000000192.blob")
expect_in("${OUT}" "<- selected")
expect_in("${OUT}" "no candidate met the limits (no demo fall, flat <= 0 of 2, mixed <= 4 of 2 falls)")
expect_choice(select_quadruped ${WORK}/walk_select 3 "candidate,stand_vx,stand_vy,stand_yaw,forward_vx")
run(2 env PBPPO=${PBPPO} bash ${select_q} ${WORK}/no-such-run)
expect_in("${ERR}" "usage: tools/select_quadruped.sh RUN_DIR")
# Flat ground alone (MIXED_ROBOTS=0) and a bound on the paper's figure: a candidate whose mean
# |error| exceeds it does not qualify, and the table shows the figures.
run(0 env PBPPO=${PBPPO} FLAT_ROBOTS=2 MIXED_ROBOTS=0 MAX_FALLS_FLAT=2 DEMO_SEEDS=1 MAX_ERROR_FLAT=0.001 bash ${select_q}
    ${WORK}/walk_select)
expect_in("${OUT}" "flat |e| vx/vy/yaw")
expect_in("${OUT}" "no candidate met the limits (no demo fall, flat <= 2 of 2, mixed <= 4 of 0 falls, flat |error| <= 0.001 per axis)")
expect_choice(select_quadruped ${WORK}/walk_select 3 "candidate,stand_vx,stand_vy,stand_yaw,forward_vx")
run(2 env PBPPO=${PBPPO} MIXED_ROBOTS=-1 bash ${select_q} ${WORK}/walk_select)
expect_in("${ERR}" "MIXED_ROBOTS: '-1' is not a non-negative integer")
run(2 env PBPPO=${PBPPO} MAX_ERROR_FLAT=low bash ${select_q} ${WORK}/walk_select)
expect_in("${ERR}" "MAX_ERROR_FLAT: 'low' is not a positive number (m/s and rad/s)")
# tools/train_quadruped.sh's polish stage: bad settings refused before anything is trained or written.
set(recipe_q ${SOURCE_DIR}/tools/train_quadruped.sh)
run(2 env PBPPO=${PBPPO} HIL=${PBPPO} POLISH_STEPS=many bash ${recipe_q} ${WORK}/walk_recipe_bad)
expect_in("${ERR}" "train_quadruped: POLISH_STEPS: 'many' is not a number of steps (0: no polish stage)")
run(2 env PBPPO=${PBPPO} HIL=${PBPPO} POLISH_STEPS=1e6 POLISH_ROBOTS=0 bash ${recipe_q} ${WORK}/walk_recipe_bad)
expect_in("${ERR}" "POLISH_ROBOTS: '0' is not a positive integer")
if(EXISTS ${WORK}/walk_recipe_bad)
  message(FATAL_ERROR "train_quadruped.sh wrote its output folder after refusing its settings")
endif()
run(2 env PBPPO=${PBPPO} "DEMO_SEEDS=1 x2" bash ${select_q} ${WORK}/walk_select)
expect_in("${ERR}" "DEMO_SEEDS: 'x2' is not a non-negative integer")
run(2 env PBPPO=${PBPPO} SCHEDULE=${WORK}/no-such.yaml bash ${select_q} ${WORK}/walk_select)
expect_in("${ERR}" "SCHEDULE: '${WORK}/no-such.yaml' is not a file")
file(MAKE_DIRECTORY ${WORK}/walk_empty)
run(2 env PBPPO=${PBPPO} bash ${select_q} ${WORK}/walk_empty)
expect_in("${ERR}" "holds no policy.blob and no snapshots/*.blob")
# A candidate that is not a walking policy (the pendulum's blob): its evaluation fails, and so does
# the choice, writing nothing.
file(COPY ${WORK}/run1/policy.blob DESTINATION ${WORK}/walk_empty)
run(2 env PBPPO=${PBPPO} FLAT_ROBOTS=2 MIXED_ROBOTS=2 DEMO_SEEDS=1 bash ${select_q} ${WORK}/walk_empty)
expect_in("${ERR}" "select_quadruped: pbppo eval ${WORK}/walk_empty/policy.blob --schedule")
expect_in("${ERR}" "an evaluation failed (above)")
if(EXISTS ${WORK}/walk_empty/selected.blob OR EXISTS ${WORK}/walk_empty/select.csv)
  message(FATAL_ERROR "select_quadruped wrote a choice after a failed evaluation")
endif()
# Same seed and thread count: byte-identical quadruped blobs (Pb-PPO, the adaptive rate, minibatches
# of 2304 in column chunks over both threads, as the shipped recipe trains).
foreach(k a b)
  run(0 ${PBPPO} train --env quadruped-walk --schedule pbppo --arms 0.1:0.3:3 --feedback rollout --steps 4608
      --envs 96 --rollout 24 --minibatch 2304 --epochs 2 --hidden 16-16 --activation elu
      --lr-schedule adaptive:0.01 --seed 2 --threads 2 --no-plots --quiet --out ${WORK}/walk_det_${k})
endforeach()
expect_same_bytes(${WORK}/walk_det_a/policy.blob ${WORK}/walk_det_b/policy.blob
                  "two quadruped-walk runs with the same seed and threads wrote different blobs")
run(2 ${PBPPO} train --env quadruped-walk --terrain stairs --steps 384 --envs 8 --rollout 24 --quiet
    --out ${WORK}/walk_bad)
expect_in("${ERR}" "stairs")
# --command-shares: half the yaw rates drawn, a fifth of the commands standing or turning in place,
# recorded in the provenance; bad shares and environments without commands refused.
run(0 ${PBPPO} train --env quadruped-walk --command-shares 0.5:0.2 --schedule fixed:0.2 --steps 384 --envs 8 --rollout 24
    --minibatch 96 --epochs 1 --hidden 16-16 --activation elu --seed 1 --threads 2 --no-plots --quiet
    --out ${WORK}/walk_heading)
# --reward-scales: the yaw-rate tracking weighed 1.0 and a cost for a fall, recorded in the
# provenance and summary.json; an unknown term, a bad value and other environments refused.
run(0 ${PBPPO} train --env quadruped-walk --command-shares 0.5:0.2 --reward-scales tracking_ang_vel=1.0,termination=-2
    --schedule fixed:0.2 --steps 384 --envs 8 --rollout 24 --minibatch 96 --epochs 1 --hidden 16-16 --activation elu
    --seed 1 --threads 2 --no-plots --quiet --out ${WORK}/walk_heading)
run(0 ${PBPPO} inspect ${WORK}/walk_heading/policy.blob)
expect_in("${OUT}" "commands every 5 s (0.5 heading, 0.2 zero planar); rewards tracking_ang_vel=1.0,termination=-2; noise")
expect_json(${WORK}/walk_heading/summary.json reward_scales "tracking_ang_vel=1.0,termination=-2")
# Another robot, named in the provenance; a provenance longer than the blob's 256 bytes is cut
# saying so ("..."), and summary.json holds it whole.
run(0 ${PBPPO} train --env quadruped-walk --robot go2 --command-shares 0.5:0.2 --command-resample 2.5
    --reward-scales tracking_lin_vel=2.5,tracking_ang_vel=1.0,termination=-150 --schedule fixed:0.2 --steps 384
    --envs 8 --rollout 24 --minibatch 96 --epochs 1 --hidden 16-16 --activation elu --seed 1 --threads 2 --no-plots
    --quiet --out ${WORK}/walk_go2)
run(0 ${PBPPO} inspect ${WORK}/walk_go2/policy.blob)
expect_in("${OUT}" "environment quadruped-walk, robot go2, terrain flat, commands every 2.5 s (0.5 heading, 0.2 zero planar); rewards tracking_lin_vel=2.5,")
string(REGEX MATCH "environment ([^\n]*)" line "${OUT}")
string(LENGTH "${CMAKE_MATCH_1}" n)
if(NOT n EQUAL 256 OR NOT CMAKE_MATCH_1 MATCHES "[.][.][.]$")
  message(FATAL_ERROR "a long provenance: ${n} bytes, not 256 ending in '...': ${CMAKE_MATCH_1}")
endif()
file(READ ${WORK}/walk_go2/summary.json json)
string(JSON whole GET "${json}" provenance)
expect_in("${whole}" "robot go2, terrain flat")
expect_in("${whole}" ", pushes 1 m/s/15 s")
expect_json(${WORK}/walk_go2/summary.json command_resample "2.5")
run(2 ${PBPPO} train --env quadruped-walk --command-resample 0 --steps 192 --quiet --out ${WORK}/walk_bad)
expect_in("${ERR}" "--command-resample: '0' is not a period in [0.02, 3600] s")
run(2 ${PBPPO} eval ${WORK}/walk_go2/policy.blob --env quadruped-walk --robot go2 --command-resample 2.5)
expect_in("${ERR}" "--command-resample")
run(2 ${PBPPO} train --env quadruped-walk --reward-scales tracking_yaw=1 --steps 192 --quiet --out ${WORK}/walk_bad)
expect_in("${ERR}" "--reward-scales: 'tracking_yaw' is not a reward term (tracking_lin_vel, tracking_ang_vel, ")
run(2 ${PBPPO} train --env quadruped-walk --reward-scales torques=-2e-4,collision=x --steps 192 --quiet
    --out ${WORK}/walk_bad)
expect_in("${ERR}" "--reward-scales: collision: 'x' is not a number")
run(2 ${PBPPO} train --env quadruped-walk --reward-scales tracking_sigma=0 --steps 192 --quiet --out ${WORK}/walk_bad)
expect_in("${ERR}" "--reward-scales: tracking_sigma: '0' is not in [1e-06, 100]")
run(2 ${PBPPO} train --env quadruped-walk --reward-scales torques --steps 192 --quiet --out ${WORK}/walk_bad)
expect_in("${ERR}" "--reward-scales: 'torques' is not NAME=VALUE (e.g. tracking_ang_vel=1.0)")
run(2 ${PBPPO} train --env hopper --reward-scales torques=0 --steps 192 --quiet --out ${WORK}/walk_bad)
expect_in("${ERR}" "--reward-scales: only quadruped-walk has reward scales to set, not 'hopper'")
run(2 ${PBPPO} train --env quadruped-walk --command-shares 0.5:2 --steps 192 --quiet --out ${WORK}/walk_bad)
expect_in("${ERR}" "--command-shares: '0.5:2': zero planar share '2' is not a number in [0, 1]")
run(2 ${PBPPO} train --env quadruped-walk --command-shares 0.5:0.2:x --steps 192 --quiet --out ${WORK}/walk_bad)
expect_in("${ERR}" "--command-shares: '0.5:0.2:x': single axis share 'x' is not a number in [0, 1]")
run(2 ${PBPPO} train --env quadruped-walk --command-shares 0.5 --steps 192 --quiet --out ${WORK}/walk_bad)
expect_in("${ERR}" "'0.5' is not HEADING_SHARE:ZERO_PLANAR_SHARE[:SINGLE_AXIS_SHARE] (e.g. 0.5:0.2)")
run(2 ${PBPPO} train --env pendulum --command-shares 1:0 --steps 192 --quiet --out ${WORK}/walk_bad)
expect_in("${ERR}" "--command-shares: only quadruped-walk has velocity commands, not 'pendulum'")
run(2 ${PBPPO} eval ${WORK}/walk/policy.blob --env quadruped-walk --commands 1:9:1)
expect_in("${ERR}" "'1:9:1': vy '9' is not a number in [0, 5]")
run(1 ${PBPPO} eval ${WORK}/run1/policy.blob --env quadruped-walk --episodes 1)
expect_in("${ERR}" "policy does not fit robot layout 'quadruped'")

# MuJoCo tasks: a tiny hopper run; its evaluation ends episodes at terminations, or with
# --through-ends runs every episode its 1000 steps (the paper's released evaluation).
run(0 ${PBPPO} train --env hopper --schedule fixed:0.2 --steps 2048 --rollout 2048 --epochs 1 --no-plots --quiet
    --out ${WORK}/hopper)
run(0 ${PBPPO} eval ${WORK}/hopper/policy.blob --env hopper --episodes 2 --json)
string(JSON steps GET "${OUT}" steps)
if(NOT steps LESS 2000)
  message(FATAL_ERROR "an untrained hopper stayed up 2 x 1000 steps (${steps})")
endif()
run(0 ${PBPPO} eval ${WORK}/hopper/policy.blob --env hopper --episodes 2 --through-ends --json)
string(JSON steps GET "${OUT}" steps)
string(JSON through GET "${OUT}" through_ends)
if(NOT steps EQUAL 2000 OR NOT through)
  message(FATAL_ERROR "eval --through-ends: ${steps} steps, through_ends ${through}")
endif()
run(2 ${PBPPO} eval ${WORK}/run1/policy.blob --env pendulum --through-ends)
expect_in("${ERR}" "--through-ends: only hopper, walker2d, half-cheetah and ant step on after an episode ends, not 'pendulum'")
# --kernel picks the forward kernel (the figures of a chaotic task differ between kernels).
run(0 ${PBPPO} eval ${WORK}/hopper/policy.blob --env hopper --episodes 1 --kernel portable --json)
string(JSON kernel GET "${OUT}" kernel)
if(NOT kernel STREQUAL "portable")
  message(FATAL_ERROR "eval --kernel portable ran the '${kernel}' kernel")
endif()
run(0 ${PBPPO} eval ${WORK}/hopper/policy.blob --env hopper --episodes 1)
expect_in("${OUT}" " kernel")
run(2 ${PBPPO} eval ${WORK}/hopper/policy.blob --env hopper --kernel sse9)
expect_in("${ERR}" "--kernel: sse9 not in {auto,portable,avx512,neon}")
run(2 ${PBPPO} eval ${WORK}/hopper/policy.blob --env hopper --contact-forces zero)
expect_in("${ERR}" "--contact-forces: only ant has contact forces to leave out, not 'hopper'")

message(STATUS "pbppo cli: all checks passed")
