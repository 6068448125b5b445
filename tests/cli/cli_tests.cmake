# Command-line tests of the mpsfsi program (label unit): every shipped case passes `mpsfsi check`;
# each kind of bad input gives a message naming file, line, key and expected form, and exit code 2.
add_test(NAME check_all_shipped_cases
         COMMAND ${CMAKE_COMMAND} -DMODE=check -DMPSFSI=$<TARGET_FILE:mpsfsi> -DCASES_DIR=${PROJECT_SOURCE_DIR}/cases
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/cli/all_cases.cmake)
set_tests_properties(check_all_shipped_cases PROPERTIES LABELS unit)

function(mpsfsi_cli_test name code regex)
  list(JOIN ARGN "|" cmd)
  add_test(NAME cli_${name}
           COMMAND ${CMAKE_COMMAND} "-DCMD=$<TARGET_FILE:mpsfsi>|${cmd}" "-DCODE=${code}" "-DREGEX=${regex}"
                   -P ${CMAKE_CURRENT_SOURCE_DIR}/cli/expect.cmake)
  set_tests_properties(cli_${name} PROPERTIES LABELS unit)
endfunction()

set(bad ${CMAKE_CURRENT_SOURCE_DIR}/cli/bad)
mpsfsi_cli_test(nonpositive_dp 2 "nonpositive_dp.yaml:[0-9]+: dp = -0.004: expected a positive number" check ${bad}/nonpositive_dp.yaml)
mpsfsi_cli_test(unknown_key 2 "unknown_key.yaml:[0-9]+: unknown key 'tme'.*expected" check ${bad}/unknown_key.yaml)
mpsfsi_cli_test(missing_key 2 "missing_key.yaml:[0-9]+: missing key 'end' in time; expected" check ${bad}/missing_key.yaml)
mpsfsi_cli_test(wrong_type 2 "wrong_type.yaml:[0-9]+: gravity = down: expected a vector" check ${bad}/wrong_type.yaml)
mpsfsi_cli_test(overlapping_bodies 2 "overlapping_bodies.yaml:[0-9]+: bodies\\[1\\].rectangle overlaps bodies\\[0\\]" check ${bad}/overlapping_bodies.yaml)
mpsfsi_cli_test(set_bad_value 2 "--set dp=0.*expected a positive number" check ${PROJECT_SOURCE_DIR}/cases/dam_break.yaml --set dp=0)
mpsfsi_cli_test(set_unknown_key 2 "unknown key 'nosuch'" check ${PROJECT_SOURCE_DIR}/cases/dam_break.yaml --set nosuch=1)
mpsfsi_cli_test(dp_not_a_number 2 "--dp" run ${PROJECT_SOURCE_DIR}/cases/dam_break.yaml --dp abc)
mpsfsi_cli_test(missing_case_file 2 "nonexistent.yaml" check nonexistent.yaml)
mpsfsi_cli_test(no_subcommand 2 "subcommand")
mpsfsi_cli_test(help 0 "run.*check" --help)
mpsfsi_cli_test(version 0 "mpsfsi [0-9]+\\.[0-9]+\\.[0-9]+.* \\(2D\\)" --version)
# The 3D cases (cases/3d/, which the glob of check_all_shipped_cases does not reach): the 2D program hands
# them to the 3D program built beside it (app/dimension_launch.hpp), for check, run and --restart alike, also
# under mpirun; a 2D build without it refuses them for their dimension, before their 3D vectors are read.
file(GLOB cases_3d ${PROJECT_SOURCE_DIR}/cases/3d/*.yaml)
if(MPSFSI_WITH_3D)
  mpsfsi_cli_test(version_names_the_3d_program 0 "\\(2D\\)\n3D program: [^\n]*/3d/mpsfsi \\(started for cases with dimension: 3\\)"
    --version)
  mpsfsi_cli_test(3d_case_checked 0 "case dam_break_3d .*total: [0-9]+ particles"
    check ${PROJECT_SOURCE_DIR}/cases/3d/dam_break.yaml)
  set(runs3d ${CMAKE_CURRENT_BINARY_DIR}/cli_runs_3d)
  mpsfsi_cli_test(3d_case_run 0 "\\(3D\\): case hydrostatic_3d.*run summary: [0-9]+ steps to t = 0\\.02 s"
    run ${PROJECT_SOURCE_DIR}/cases/3d/hydrostatic.yaml --overwrite --output ${runs3d}/hydrostatic --end-time 0.02
    --checkpoint-every 0.01)
  set_tests_properties(cli_3d_case_run PROPERTIES FIXTURES_SETUP cli_3d_checkpoint)
  # The checkpoint alone (no case file) tells its dimension.
  mpsfsi_cli_test(3d_case_restart 0 "\\(3D\\): case hydrostatic_3d.*run summary: [0-9]+ steps to t = 0\\.03 s"
    run --restart ${runs3d}/hydrostatic/checkpoint_0.02.chk --output ${runs3d}/hydrostatic_restart --overwrite
    --end-time 0.03)
  set_tests_properties(cli_3d_case_restart PROPERTIES FIXTURES_REQUIRED cli_3d_checkpoint)
  # --set dimension=3 on a 2D case is the 3D program's to refuse (its 2D vectors).
  mpsfsi_cli_test(3d_set_on_a_2d_case 2 "hydrostatic\\.yaml:[0-9]+: domain\\.min = \\[-0\\.05, -0\\.05\\]: expected the lowest corner \\[x, y, z\\]"
    check ${PROJECT_SOURCE_DIR}/cases/hydrostatic.yaml --set dimension=3)
  add_test(NAME cli_mpi_3d_case_run
           COMMAND ${CMAKE_COMMAND} "-DCMD=${MPIEXEC_EXECUTABLE}|--allow-run-as-root|--oversubscribe|${MPIEXEC_NUMPROC_FLAG}|2|$<TARGET_FILE:mpsfsi>|run|${PROJECT_SOURCE_DIR}/cases/3d/hydrostatic.yaml|--overwrite|--output|${runs3d}/hydrostatic_np2|--end-time|0.01"
                   -DCODE=0 "-DREGEX=\\(3D\\): case hydrostatic_3d \\([0-9]+ particles\\)" -DONCE=1 -P ${CMAKE_CURRENT_SOURCE_DIR}/cli/expect.cmake)
  set_tests_properties(cli_mpi_3d_case_run PROPERTIES LABELS mpi PROCESSORS 2)
else()
  foreach(f IN LISTS cases_3d)
    get_filename_component(n ${f} NAME_WE)
    mpsfsi_cli_test(3d_case_${n}_refused 2
      "${n}\\.yaml:[0-9]+: dimension = 3: this mpsfsi is built for 2D \\(MPSFSI_DIM=2\\); expected a 2D case .*3D cases run in the 3D program"
      check ${f})
  endforeach()
endif()

# Under mpirun an input error is printed once (by rank 0), not by every rank.
add_test(NAME cli_mpi_input_error_printed_once
         COMMAND ${CMAKE_COMMAND} "-DCMD=${MPIEXEC_EXECUTABLE}|--allow-run-as-root|--oversubscribe|${MPIEXEC_NUMPROC_FLAG}|2|$<TARGET_FILE:mpsfsi>|check|${PROJECT_SOURCE_DIR}/cases/dam_break.yaml|--set|dp=0"
                 -DCODE=2 "-DREGEX=dp = 0: expected a positive number" -DONCE=1 -P ${CMAKE_CURRENT_SOURCE_DIR}/cli/expect.cmake)
set_tests_properties(cli_mpi_input_error_printed_once PROPERTIES LABELS mpi PROCESSORS 2)
# Under mpirun `check` reports once (rank 0's report).
add_test(NAME cli_mpi_check_reports_once
         COMMAND ${CMAKE_COMMAND} "-DCMD=${MPIEXEC_EXECUTABLE}|--allow-run-as-root|--oversubscribe|${MPIEXEC_NUMPROC_FLAG}|2|$<TARGET_FILE:mpsfsi>|check|${PROJECT_SOURCE_DIR}/cases/dam_break.yaml"
                 -DCODE=0 "-DREGEX=case OK" -DONCE=1 -P ${CMAKE_CURRENT_SOURCE_DIR}/cli/expect.cmake)
set_tests_properties(cli_mpi_check_reports_once PROPERTIES LABELS mpi PROCESSORS 2)
# All ranks take the same decision on the memory (the smallest MemAvailable of any rank): one message, exit 2.
add_test(NAME cli_mpi_memory_refused_on_every_rank
         COMMAND ${CMAKE_COMMAND} "-DCMD=${MPIEXEC_EXECUTABLE}|--allow-run-as-root|--oversubscribe|${MPIEXEC_NUMPROC_FLAG}|2|$<TARGET_FILE:mpsfsi>|check|${PROJECT_SOURCE_DIR}/cases/dam_break.yaml|--dp|1e-5"
                 -DCODE=2 "-DREGEX=dp = 1e-05: the case would have" -DONCE=1 -P ${CMAKE_CURRENT_SOURCE_DIR}/cli/expect.cmake)
set_tests_properties(cli_mpi_memory_refused_on_every_rank PROPERTIES LABELS mpi PROCESSORS 2)

# Failure handling (issue 7): each kind is provoked and must give its diagnosis and a non-zero exit.
set(db ${PROJECT_SOURCE_DIR}/cases/dam_break.yaml)
set(run_dir ${CMAKE_CURRENT_BINARY_DIR}/cli_runs)
# A runaway: a fixed dt ten times the CFL limit's and a sound speed of 1 m/s, every particle kept however far it
# is flung (max_loss 1); the water passes c at step 10.
mpsfsi_cli_test(fail_runaway 3 "moves at .* m/s, faster than the fluid's sound speed.*last good frame"
  run ${db} --quiet --overwrite --output ${run_dir}/runaway --end-time 0.2 --set time.cfl=~ --set time.dt_max=~ --set time.dt=0.01
  --set fluid.max_loss=1 --set materials.water.c=1)
mpsfsi_cli_test(fail_ppe_not_converged 3 "pressure solve did not converge: 2 iterations.*last good frame"
  run ${db} --quiet --overwrite --output ${run_dir}/ppe --end-time 0.01 --set fluid.max_iterations=2)
# Water flung up out of the domain: removed and counted while at most fluid.max_loss of the body is gone, then
# the run stops with exit 3 (issue 13: it used to lose every particle and exit 0).
mpsfsi_cli_test(fluid_leaves_domain 0 "fluid particles left the domain and were removed"
  run ${PROJECT_SOURCE_DIR}/cases/hydrostatic.yaml --quiet --overwrite --output ${run_dir}/leave --end-time 0.35
  --set gravity=[0,9.81] --set "domain={min: [-0.05, -0.05], max: [0.25, 0.32]}" --set fluid.max_loss=1)
mpsfsi_cli_test(fluid_lost_stops_the_run 3 "of fluid body 'water' have left the domain.*more than fluid.max_loss = 5 %"
  run ${PROJECT_SOURCE_DIR}/cases/hydrostatic.yaml --quiet --overwrite --output ${run_dir}/lost --end-time 0.35
  --set gravity=[0,9.81] --set "domain={min: [-0.05, -0.05], max: [0.25, 0.32]}")
add_test(NAME cli_mpi_fluid_lost_stops_the_run
         COMMAND ${CMAKE_COMMAND} "-DCMD=${MPIEXEC_EXECUTABLE}|--allow-run-as-root|--oversubscribe|${MPIEXEC_NUMPROC_FLAG}|2|$<TARGET_FILE:mpsfsi>|run|${PROJECT_SOURCE_DIR}/cases/hydrostatic.yaml|--quiet|--overwrite|--output|${run_dir}/lost_mpi|--end-time|0.35|--set|gravity=[0,9.81]|--set|domain={min: [-0.05, -0.05], max: [0.25, 0.32]}"
                 -DCODE=3 "-DREGEX=more than fluid.max_loss = 5 %" -P ${CMAKE_CURRENT_SOURCE_DIR}/cli/expect.cmake)
set_tests_properties(cli_mpi_fluid_lost_stops_the_run PROPERTIES LABELS mpi PROCESSORS 2)
# A huge dt_max: the first step is limited by the gravity (acceleration), the water stays in the tank.
mpsfsi_cli_test(huge_dt_max_first_step_limited_by_gravity 0 "dt 9.03e-03 s \\(acceleration\\)"
  run ${db} --overwrite --output ${run_dir}/huge_dt_max --end-time 0.01 --set time.dt_max=1e10)

# `check` projects the steps of a run and warns when they cannot finish (water 1e9 times as viscous: dt 3.2e-9 s).
# check describes each wall's own motion: its parts, timing, largest speed, and the clamps that move with it.
mpsfsi_cli_test(check_describes_wall_motion 0
                "wall paddle: translation sine, amplitude \\[0.03, 0\\] m, period 0.4 s; start 0 s, ramp 0.1 s; largest speed about 0.544 m/s; the clamp of 'plate' moves with it"
                check ${CMAKE_CURRENT_SOURCE_DIR}/cli/cases/plate_on_paddle.yaml)
mpsfsi_cli_test(check_projection_warns 0 "projection: 3.12e\\+08 steps of dt = 3.2e-09 s \\(viscous\\).*warning: .* cannot finish in any sensible time"
  check ${db} --set materials.water.nu=1e3)

# The legacy key names its replacement.
mpsfsi_cli_test(legacy_muelu_rebuild_every 2 "fluid.muelu_rebuild_every: this key was replaced by fluid.preconditioner_rebuild_every"
  check ${db} --set fluid.muelu_rebuild_every=5)

# Command-line values that are refused (exit 2) rather than taken as defaults or as nothing.
mpsfsi_cli_test(checkpoint_every_nan 2 "--checkpoint-every.*'nan': expected a positive, finite number"
  run ${db} --output ${run_dir}/ck_nan --checkpoint-every nan)
mpsfsi_cli_test(checkpoint_every_zero 2 "--checkpoint-every.*'0': expected a positive, finite number"
  run ${db} --output ${run_dir}/ck_zero --checkpoint-every 0)
mpsfsi_cli_test(unknown_output_field 2 "output.fields: 'nosuch' is not a field of this case; expected some of: free_surface, pressure"
  run ${db} --output ${run_dir}/unknown_field --overwrite --end-time 0.01 --set "output.fields=[pressure,nosuch]")
# Output folders that cannot be one: exit 2 naming --output, not a raw filesystem error.
mpsfsi_cli_test(output_is_a_file 2 "--output /dev/null: exists and is not a folder" run ${db} --output /dev/null --end-time 0.01)
mpsfsi_cli_test(output_under_a_file 2 "--output .*dam_break.yaml/sub: cannot create the folder"
  run ${db} --output ${db}/sub --end-time 0.01)
mpsfsi_cli_test(existing_output_refused 2 "exists and is not empty.*--overwrite"
  run ${db} --quiet --output ${PROJECT_SOURCE_DIR}/cases --end-time 0.01)

# Every shipped case runs its first 20 steps at its own settings (label cases).
add_test(NAME run_all_shipped_cases
         COMMAND ${CMAKE_COMMAND} -DMODE=run -DMPSFSI=$<TARGET_FILE:mpsfsi> -DCASES_DIR=${PROJECT_SOURCE_DIR}/cases
                 -DWORK=${CMAKE_CURRENT_BINARY_DIR}/case_runs -DSTEPS=20
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/cli/all_cases.cmake)
set_tests_properties(run_all_shipped_cases PROPERTIES LABELS cases TIMEOUT 600 COST 42)  # COST: see tests/fuzz

# A run's outputs: disk full while frames are written (exit 4, complete frames only), progress lines flushed
# to a pipe, fragments.csv only for breakable solids, empty option values refused.
find_package(Python3 COMPONENTS Interpreter)
if(Python3_Interpreter_FOUND)
  add_test(NAME cli_run_outputs
           COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/cli/run_output_test.py $<TARGET_FILE:mpsfsi>
                   ${PROJECT_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR}/cli_run_outputs)
  set_tests_properties(cli_run_outputs PROPERTIES LABELS runs TIMEOUT 300)
endif()

# Issue 13: input that blocked `check`, ran it out of memory, made it take minutes, hung a run or reached the
# run before failing there is refused by `check` (exit 2) with the key and the expected form.
set(lamb ${PROJECT_SOURCE_DIR}/cases/lamb_a.yaml)
set(measured ${PROJECT_SOURCE_DIR}/cases/sloshing_high_measured.yaml)
mpsfsi_cli_test(table_from_a_device 2 "sources\\[0\\]\\.wavelet\\.file = /dev/zero: '/dev/zero' is not a regular file"
  check ${lamb} --set "sources.0.wavelet={type: table, file: /dev/zero}")
mpsfsi_cli_test(tank_table_from_a_device 2 "tank_motion\\.file = /dev/zero: '/dev/zero' is not a regular file"
  check ${measured} --set tank_motion.file=/dev/zero)
mpsfsi_cli_test(tank_table_rows_checked_before_the_run 2
  "tank_motion\\.file = .*: [^ ]*/tests/cli/bad/roll_semicolons\\.csv:3: '0\\.5;1': expected a row of two numbers: time \\[s\\], angle \\[deg\\]"
  run ${measured} --quiet --overwrite --output ${run_dir}/semicolons --end-time 0.01 --set tank_motion.file=${bad}/roll_semicolons.csv)
mpsfsi_cli_test(huge_effective_radius 2
  "fluid\\.re_laplacian = 1e6: about pi re\\^2 = 3\\.1e\\+12 neighbours per particle; expected a number in \\(1, 10\\]"
  check ${db} --set fluid.re_laplacian=1e6)
mpsfsi_cli_test(dp_too_small_for_the_memory 2
  "dam_break\\.yaml: dp = 1e-05: the case would have 427020836 particles .* and need about [0-9.]+ GiB of memory, but this machine has"
  check ${db} --dp 1e-5)
mpsfsi_cli_test(tiny_output_interval 2 "output\\.interval = 1e-300: expected an interval of at least 1e-06 s"
  check ${db} --set output.interval=1e-300)
mpsfsi_cli_test(tiny_time_step 2 "time\\.dt_max = 1e-300: expected a time step of at least 1e-12 s" check ${db} --set time.dt_max=1e-300)
mpsfsi_cli_test(huge_gravity 2 "gravity = \\[1e300, 1e300\\]: expected a vector \\[gx, gy\\] in m/s2 of magnitude at most 10000"
  check ${db} --set "gravity=[1e300, 1e300]")
string(REPEAT "a" 300 long_name)
mpsfsi_cli_test(long_case_name 2 "name = a+\\.\\.\\.: expected the case name: a name of at most 64 letters" check ${db} --set name=${long_name})
# `check` prints the extent the particles represent and warns (exit 0) when it misses the rectangle by > dp/4.
mpsfsi_cli_test(body_extent_warning 0
  "column +\\[0, 0\\.164\\] x \\[0, 0\\.292\\] m.*warning: body 'column' is represented by \\[0, 0\\.164\\] x \\[0, 0\\.292\\] m \\(0\\.164 x 0\\.292 m\\), not by its rectangle \\[0, 0\\.1625\\]"
  check ${db} --set "bodies.column.rectangle={min: [0, 0], max: [0.1625, 0.292]}")
mpsfsi_cli_test(clamped_free_length 0 "plate +\\[0\\.291, 0\\.303\\] x \\[-0\\.009, 0\\.081\\] m .*; free length 0\\.081 m along y \\(file: 0\\.08 m\\)"
  check ${PROJECT_SOURCE_DIR}/cases/dam_break_elastic_plate.yaml)

# Issue 29: signals (SIGINT / SIGTERM stop at the end of a step with a frame and a checkpoint, a second SIGINT
# at once, the same under mpirun), the output folder's lock, a folder removed mid-run, a branching restart's
# stale files, --restart on a FIFO, a case without description and source.
if(Python3_Interpreter_FOUND)
  add_test(NAME cli_run_reliability
           COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/cli/reliability_test.py $<TARGET_FILE:mpsfsi>
                   ${PROJECT_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR}/cli_run_reliability
                   ${MPIEXEC_EXECUTABLE} --allow-run-as-root --oversubscribe ${MPIEXEC_NUMPROC_FLAG} 2)
  set_tests_properties(cli_run_reliability PROPERTIES LABELS runs TIMEOUT 300)
endif()
