# Compute shaders to SPIR-V at build time, embedded in a library as comma-separated words that
# its shaders.cpp includes (glslc -mfmt=num). Every world's shaders may include the shared ones
# in src/gpu/shaders (storage.glsl) beside their own folder's.
#
#   penumbra_add_shaders(TARGET DIR EMBEDDING_SOURCE [F16 name...])
# compiles DIR/*.comp; the names after F16 are compiled once more with -DPENUMBRA_F16
# (16-bit storage), as NAME_f16.comp.inc.
find_program(GLSLC glslc REQUIRED)

function(penumbra_add_shaders target dir embedding)
  cmake_parse_arguments(ARG "" "" "F16" ${ARGN})
  set(common ${PROJECT_SOURCE_DIR}/src/gpu/shaders)
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/shaders/${target})
  file(GLOB shaders CONFIGURE_DEPENDS ${dir}/*.comp)
  file(GLOB includes CONFIGURE_DEPENDS ${dir}/*.glsl ${common}/*.glsl)
  set(outputs)
  set(variants)
  foreach(shader ${shaders})
    get_filename_component(name ${shader} NAME_WE)
    list(APPEND variants "${name}|${shader}|${name}.comp.inc|")
  endforeach()
  foreach(name ${ARG_F16})
    list(APPEND variants "${name}|${dir}/${name}.comp|${name}_f16.comp.inc|-DPENUMBRA_F16")
  endforeach()
  foreach(v ${variants})
    string(REPLACE "|" ";" parts "${v}")
    list(GET parts 1 shader)
    list(GET parts 2 inc)
    list(LENGTH parts n)
    set(define)
    if(n GREATER 3)
      list(GET parts 3 define)
    endif()
    set(out ${out_dir}/${inc})
    add_custom_command(OUTPUT ${out}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${out_dir}
      COMMAND ${GLSLC} -fshader-stage=compute --target-env=vulkan1.1 -O -Werror -mfmt=num
              ${define} -I ${dir} -I ${common} -o ${out} ${shader}
      DEPENDS ${shader} ${includes}
      COMMENT "glslc ${inc}")
    list(APPEND outputs ${out})
  endforeach()
  target_sources(${target} PRIVATE ${outputs})
  set_source_files_properties(${embedding} PROPERTIES OBJECT_DEPENDS "${outputs}")
  target_include_directories(${target} PRIVATE ${out_dir})
endfunction()
