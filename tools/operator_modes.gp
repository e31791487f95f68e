# The controller's phases and the operator's requests, as docs/operator.md shows them:
#   gnuplot tools/operator_modes.gp   (writes docs/images/operator_modes.png)
set terminal pngcairo size 1000,480 font "DejaVu Sans,10" noenhanced
set output "docs/images/operator_modes.png"
unset border; unset xtics; unset ytics; unset key
set xrange [0:100]; set yrange [0:48]
set lmargin 0; set rmargin 0; set tmargin 0; set bmargin 0
set style arrow 1 head filled size 1,15 lw 1.3 lc rgb "#333333"
set style arrow 2 head filled size 1,15 lw 1.3 lc rgb "#c0392b"
# A phase: a box at (x, y) with its name.
box(n, x, y, w, c) = sprintf("set object %d rect center %f,%f size %f,4 fc rgb '%s' fs solid 0.25 border lc rgb '%s'", n, x, y, w, c, c)
eval box(1, 7, 26, 11, "#2a6ebb");  set label "disarmed" at 7,26 center
eval box(2, 25, 26, 11, "#2a6ebb"); set label "arming" at 25,26 center
eval box(3, 43, 26, 11, "#2a6ebb"); set label "stand-up" at 43,26 center
eval box(4, 61, 26, 11, "#2a6ebb"); set label "hold" at 61,26 center
eval box(5, 88, 26, 14, "#2a8a2a"); set label "run (the policy)" at 88,26 center
eval box(6, 43, 10, 11, "#2a6ebb"); set label "damping" at 43,10 center
eval box(7, 61, 10, 11, "#2a6ebb"); set label "motor-off" at 61,10 center
eval box(8, 88, 10, 11, "#2a6ebb"); set label "done" at 88,10 center
eval box(10, 80, 42, 11, "#2a6ebb"); set label "sit-down" at 80,42 center
eval box(11, 54, 42, 15, "#8a6d2a"); set label "passive (damped)" at 54,42 center
set object 9 rect center 14,10 size 24,6 fc rgb "#c0392b" fs solid 0.15 border lc rgb "#c0392b"
set label "e-stop (latched): damping" at 14,11 center tc rgb "#c0392b" font ",10:Bold"
set label "BACK, from any phase" at 14,8.6 center tc rgb "#c0392b" font ",9"
# Transitions and what asks for them.
set arrow from 12.5,26 to 19.5,26 as 1; set label "START (arm)" at 16,28.4 center font ",9"
set arrow from 30.5,26 to 37.5,26 as 1; set label "motors answer" at 34,28.4 center font ",9"
set arrow from 48.5,26 to 55.5,26 as 1; set label "pose reached" at 52,28.4 center font ",9"
set arrow from 66.5,26 to 81,26 as 1; set label "A (walk), LB held" at 73.7,28.4 center font ",9"
set label "RB: the next policy," at 90,21.3 center font ",9"
set label "blended in" at 90,19.3 center font ",9"
set arrow from 88,28 to 88,33 nohead lw 1.3 lc rgb "#333333"
set arrow from 88,33 to 43,33 nohead lw 1.3 lc rgb "#333333"
set arrow from 43,33 to 43,28 as 1
set label "LB released: stand up from the measured pose, then hold (A with LB walks again)" at 65.5,35 center font ",9"
set arrow from 61,24 to 46,12 as 1
set arrow from 84,24 to 48.5,11 as 1; set label "B (stop; also from sit-down, passive)" at 66,18.5 center font ",9"
set arrow from 48.5,10 to 55.5,10 as 1; set label "0.5 s" at 52,7.8 center font ",9"
set arrow from 66.5,10 to 82.5,10 as 1; set label "motors answer" at 74.5,12.2 center font ",9"
set arrow from 20,13 to 24,24 as 2; set label "Xbox (re-arm), 0.5 s healthy" at 26,17.5 left tc rgb "#c0392b" font ",9"
set arrow from 21,28 to 21,43 nohead lw 1.3 lc rgb "#c0392b"
set arrow from 21,43 to 46.5,43 as 2; set label "re-armed: passive (rearm_to)" at 22,44.6 left tc rgb "#c0392b" font ",9"
set label "Sticks: left up/down vx, left left/right vy, right left/right yaw rate; dead zone 10 %, 1 m/s per s. The pad gone: command 0 and LB released, so the robot stands." at 1,2.5 left font ",9"
# Sitting down and standing up again.
set arrow from 64,28 to 76,40 as 1
set arrow from 90,28 to 84,40 as 1; set label "R3 (sit), from stand-up, hold or run" at 95,45.5 right font ",9"
set arrow from 74.5,42 to 61.5,42 as 1; set label "sit pose reached" at 68,44.4 center font ",9"
set arrow from 46.5,41 to 43,28 as 1; set label "START: stand up from where it sits" at 44.5,39 right font ",9"
set label "The controller's phases and the operator's requests (models/quadruped_gamepad)" at 50,47 center font ",11:Bold"
plot -10 notitle
