find_program(FASTDDSGEN fastddsgen REQUIRED)

# mrslam_generate_idl(<target> <idl files...>): runs fastddsgen at build time into the build
# tree and builds a static library from its output. Regenerates only when an IDL file changes.
function(mrslam_generate_idl target)
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/generated)
  set(sources)
  foreach(idl ${ARGN})
    get_filename_component(name ${idl} NAME_WE)
    get_filename_component(idl_abs ${idl} ABSOLUTE)
    set(outs ${out_dir}/${name}.cxx ${out_dir}/${name}.h
             ${out_dir}/${name}PubSubTypes.cxx ${out_dir}/${name}PubSubTypes.h)
    add_custom_command(
      OUTPUT ${outs}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${out_dir}
      COMMAND ${FASTDDSGEN} -replace -cs -d ${out_dir} ${idl_abs} > ${out_dir}/${name}.log
      DEPENDS ${idl_abs}
      COMMENT "fastddsgen ${name}.idl"
      VERBATIM)
    list(APPEND sources ${out_dir}/${name}.cxx ${out_dir}/${name}PubSubTypes.cxx)
  endforeach()
  add_library(${target} STATIC ${sources})
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  target_include_directories(${target} SYSTEM PUBLIC ${out_dir})
  target_link_libraries(${target} PUBLIC fastcdr fastrtps)
endfunction()
