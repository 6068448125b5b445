# Command-line tests of the mpsfsi program (label unit).
foreach(case_name dam_break hydrostatic dam_break_obstacle)
  add_test(NAME check_${case_name} COMMAND mpsfsi check ${PROJECT_SOURCE_DIR}/cases/${case_name}.yaml)
  set_tests_properties(check_${case_name} PROPERTIES LABELS unit)
endforeach()
