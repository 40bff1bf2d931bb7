# SPDX-License-Identifier: Apache-2.0
# The layering rules of docs/architecture.md, checked by the `lint.layering` test.
#
# At configure time every guarded library's transitive link closure (what the linker will really
# pull in) and its source and header files are written to build/layering/<target>.txt; the test
# (cmake/check_layering.cmake) matches them against the rules below. A dependency added to a
# CMakeLists.txt or an #include added to a source reaches the test through the next build.

# Dependencies that mean DDS, the simulator, command-line parsing or file I/O.
set(_panoptes_dds_links "panoptes_dds|panoptes_msgs|fastrtps|fastcdr|panoptes_camera_app|panoptes_estimator_app")
set(_panoptes_io_links "panoptes_io|panoptes_common|panoptes_session|yaml-cpp|nlohmann_json|opencv_imgcodecs|opencv_highgui|opencv_videoio|spdlog")
set(_panoptes_pure_links "${_panoptes_dds_links}|${_panoptes_io_links}|panoptes_sim|panoptes_evaluation|CLI11")
# Includes and calls that mean the same in a source or header.
set(_panoptes_pure_sources
  "#include [<\"](fastdds/|fastrtps/|fastcdr/|panoptes_msgs/|CLI/|yaml-cpp/|nlohmann/|spdlog/|fstream|filesystem|opencv2/imgcodecs|opencv2/highgui|opencv2/videoio|panoptes/dds/|panoptes/simulator\\.h|panoptes/config\\.h|panoptes/jsonl\\.h|panoptes/calibration_file\\.h|panoptes/process\\.h|panoptes/cli\\.h)|std::(i|o)?fstream|[^_a-z]fopen *\\(")

# target | forbidden links (regex) | forbidden source text (regex, empty: none) | why
set(PANOPTES_LAYERING_RULES
  "panoptes_core|${_panoptes_pure_links}|opencv|Ceres|${_panoptes_pure_sources}|the core holds types and maths only"
  "panoptes_estimator|${_panoptes_pure_links}|opencv|Ceres|${_panoptes_pure_sources}|the estimator core runs identically live, offline and in tests: no DDS, simulator, CLI or file I/O"
  "panoptes_calib|${_panoptes_pure_links}|${_panoptes_pure_sources}|calibration maths: no DDS, simulator, CLI or file I/O"
  "panoptes_planner|${_panoptes_pure_links}|opencv|Ceres|${_panoptes_pure_sources}|placement maths: no DDS, simulator, CLI or file I/O"
  "panoptes_surface|${_panoptes_pure_links}|opencv|Ceres|${_panoptes_pure_sources}|surface (LumiPoint) tracking runs identically live, offline and in tests: no DDS, simulator, CLI or file I/O"
  "panoptes_labelling|${_panoptes_pure_links}|opencv|Ceres|${_panoptes_pure_sources}|marker sets and subject models run identically live, offline and in tests: no DDS, simulator, CLI or file I/O"
  "panoptes_labelling_files|${_panoptes_dds_links}|panoptes_sim|CLI11||the marker set and subject model files are read without DDS (estimator session, panoptes_label)"
  "panoptes_ptz|${_panoptes_dds_links}|panoptes_sim|panoptes_evaluation|CLI11|opencv|Ceres|#include [<\"](fastdds/|fastrtps/|fastcdr/|panoptes_msgs/|panoptes/dds/|CLI/|panoptes/simulator\\.h)|PTZ guidance (model, prediction, simulated head) runs without DDS, simulator or CLI: ptz_guide and panoptes_sim adapt it"
  "panoptes_io|${_panoptes_dds_links}||only panoptes_dds knows DDS"
  "panoptes_sim|${_panoptes_dds_links}||only panoptes_dds knows DDS"
  "panoptes_mocap_formats|${_panoptes_dds_links}|panoptes_sim|panoptes_evaluation|CLI11|#include [<\"](fastdds/|fastrtps/|fastcdr/|panoptes_msgs/|panoptes/dds/|CLI/|panoptes/simulator\\.h)|file formats: files only, no DDS, simulator or CLI"
  "panoptes_camera|${_panoptes_dds_links}||the camera pipeline runs without DDS (offline mode, tests)"
  "panoptes_evaluation|${_panoptes_dds_links}||only panoptes_dds knows DDS"
  "panoptes_session|${_panoptes_dds_links}||the estimator session runs without DDS (offline mode, tests)"
  "panoptes_console_server|${_panoptes_dds_links}|panoptes_sim|CLI11|#include [<\"](fastdds/|fastrtps/|panoptes_msgs/|panoptes/dds/|CLI/)|the console's state and server run without DDS (tests), panoptes_console_app adapts the bus"
  "panoptes_tune|${_panoptes_dds_links}||filter tuning replays recordings offline: no DDS"
  "panoptes_recording|${_panoptes_dds_links}|panoptes_sim|panoptes_evaluation|CLI11|opencv|Ceres|#include [<\"](fastdds/|fastrtps/|fastcdr/|panoptes_msgs/|panoptes/dds/|CLI/)|MCAP files are read and written without DDS (offline tools, estimator_node --in-recording)"
  "panoptes_client|${_panoptes_io_links}|panoptes_sim|panoptes_evaluation|CLI11|opencv|Ceres|#include [<\"](CLI/|yaml-cpp/|nlohmann/|spdlog/|fstream|opencv2/|panoptes/jsonl\\.h|panoptes/config\\.h)|the client library applications link: the bus and its messages, no file formats, simulator or CLI"
  "panoptes_python|${_panoptes_io_links}|panoptes_sim|panoptes_evaluation|CLI11|opencv|Ceres|#include [<\"](fastdds/|fastrtps/|fastcdr/|panoptes_msgs/|panoptes/dds/|CLI/|yaml-cpp/|nlohmann/)|the Python binding uses the public client API only")

# Generated rules (panoptes_layering_manifest), from where each library's folder is:
# - tools/ sits above the nodes: a tool's library may link any library below it, but no library in
#   idl/, common/, camera_node/ or estimator_node/ links a library in tools/.
# - The console and the recorder serve the whole bus through its messages: they link no library of
#   camera_node/ or estimator_node/ (so a change to them rebuilds no node library, and the reverse).
set(PANOPTES_LAYERING_BUS_TOOLS panoptes_console_server panoptes_console_app panoptes_recorder)

# Every library target defined in `dir` or below, into `out_var`.
function(_panoptes_libraries dir out_var)
  set(found "")
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  foreach(target ${targets})
    get_target_property(type ${target} TYPE)
    if(type MATCHES "_LIBRARY$")
      list(APPEND found ${target})
    endif()
  endforeach()
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(subdir ${subdirs})
    _panoptes_libraries(${subdir} below)
    list(APPEND found ${below})
  endforeach()
  set(${out_var} ${found} PARENT_SCOPE)
endfunction()

# PANOPTES_LAYERING_RULES plus the generated rules above, into `out_var`.
function(_panoptes_layering_rules out_var)
  set(rules ${PANOPTES_LAYERING_RULES})
  _panoptes_libraries(${CMAKE_SOURCE_DIR}/tools tool_libraries)
  set(node_libraries "")
  foreach(dir camera_node estimator_node)
    _panoptes_libraries(${CMAKE_SOURCE_DIR}/${dir} found)
    list(APPEND node_libraries ${found})
  endforeach()
  set(lower_libraries ${node_libraries})
  foreach(dir idl common)
    _panoptes_libraries(${CMAKE_SOURCE_DIR}/${dir} found)
    list(APPEND lower_libraries ${found})
  endforeach()
  string(REPLACE ";" "|" tool_regex "${tool_libraries}")
  string(REPLACE ";" "|" node_regex "${node_libraries}")
  if(tool_regex)
    foreach(target ${lower_libraries})
      list(APPEND rules "${target}|${tool_regex}||tools/ sits above the nodes and common/: no library below it links a tool's library")
    endforeach()
  endif()
  foreach(target ${PANOPTES_LAYERING_BUS_TOOLS})
    if(NOT target IN_LIST tool_libraries)
      message(FATAL_ERROR "layering: ${target} (PANOPTES_LAYERING_BUS_TOOLS) is not a library in tools/")
    endif()
    list(APPEND rules "${target}|${node_regex}||the console and the recorder serve the whole bus through its messages: no node library")
  endforeach()
  set(${out_var} ${rules} PARENT_SCOPE)
endfunction()

# Transitive link closure of `target` (names of targets and libraries) into `out_var`.
function(_panoptes_link_closure target out_var)
  set(seen "")
  set(queue ${target})
  while(queue)
    list(POP_FRONT queue item)
    if(item IN_LIST seen)
      continue()
    endif()
    list(APPEND seen ${item})
    if(TARGET ${item})
      get_target_property(aliased ${item} ALIASED_TARGET)
      if(aliased)
        list(APPEND queue ${aliased})
      endif()
      set(deps "")
      get_target_property(type ${item} TYPE)
      if(NOT type STREQUAL "INTERFACE_LIBRARY")
        get_target_property(direct ${item} LINK_LIBRARIES)
        if(direct)
          list(APPEND deps ${direct})
        endif()
      endif()
      get_target_property(interface ${item} INTERFACE_LINK_LIBRARIES)
      if(interface)
        list(APPEND deps ${interface})
      endif()
      foreach(dep ${deps})
        # $<LINK_ONLY:x> (private deps of static libraries) still reach the final link.
        string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" dep "${dep}")
        if(dep MATCHES "^\\$<" OR dep STREQUAL "")
          continue()
        endif()
        list(APPEND queue ${dep})
      endforeach()
    endif()
  endwhile()
  list(REMOVE_ITEM seen ${target})
  set(${out_var} ${seen} PARENT_SCOPE)
endfunction()

# Writes build/layering/<target>.txt for every guarded target that exists, and registers the test.
function(panoptes_layering_manifest)
  set(dir ${CMAKE_BINARY_DIR}/layering)
  file(MAKE_DIRECTORY ${dir})
  set(rules_file ${dir}/rules.txt)
  _panoptes_layering_rules(rules)
  string(REPLACE ";" "\n" rules_text "${rules}")
  file(WRITE ${rules_file} "${rules_text}\n")
  set(written "")
  foreach(rule ${rules})
    string(REGEX MATCH "^[^|]+" target "${rule}")
    if(NOT TARGET ${target} OR target IN_LIST written)
      continue()
    endif()
    list(APPEND written ${target})
    _panoptes_link_closure(${target} closure)
    set(text "")
    foreach(link ${closure})
      string(APPEND text "link ${link}\n")
    endforeach()
    get_target_property(source_dir ${target} SOURCE_DIR)
    get_target_property(sources ${target} SOURCES)
    if(NOT sources)
      set(sources "")  # an INTERFACE library
    endif()
    foreach(source ${sources})
      get_filename_component(path ${source} ABSOLUTE BASE_DIR ${source_dir})
      string(APPEND text "file ${path}\n")
    endforeach()
    file(GLOB_RECURSE headers ${source_dir}/include/*.h ${source_dir}/src/*.h)
    foreach(header ${headers})
      string(APPEND text "file ${header}\n")
    endforeach()
    file(WRITE ${dir}/${target}.txt "${text}")
  endforeach()
endfunction()
