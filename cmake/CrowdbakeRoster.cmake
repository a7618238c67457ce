# crowdbake_bake_roster(TARGET CATALOG OUTPUT_DIR DIR [MANIFEST FILE] [OPTIONS opt...])
#
# Bakes a catalog (catalog.example.toml) as a build step: palettes and roster.json in DIR (the
# catalog's out_dir is replaced), re-run when the catalog, a model, a LOD or an external buffer
# changes. crowdbake writes a depfile listing every file it read, so the build tool knows them
# without configure-time globbing; and crowdbake itself re-bakes only the types whose inputs
# changed (each palette records a hash of its inputs): touching one model re-bakes its types,
# and a second build does nothing. OPTIONS are more `crowdbake bake` options (-j 4,
# --format pal,exr, ...). The command is crowdbake::cli (find_package(crowdbake)), or
# CROWDBAKE_EXECUTABLE when set. TARGET is a target that is ALL; its CROWDBAKE_MANIFEST property
# names the manifest, for install() or for a game's asset step.
function(crowdbake_bake_roster target catalog)
  cmake_parse_arguments(PARSE_ARGV 2 arg "" "OUTPUT_DIR;MANIFEST" "OPTIONS")
  if(NOT arg_OUTPUT_DIR)
    message(FATAL_ERROR "crowdbake_bake_roster(${target} ${catalog}): give OUTPUT_DIR, where the palettes go")
  endif()
  if(CROWDBAKE_EXECUTABLE)
    set(exe "${CROWDBAKE_EXECUTABLE}")
  elseif(TARGET crowdbake::cli)
    set(exe crowdbake::cli)
  else()
    message(FATAL_ERROR "crowdbake_bake_roster: no crowdbake command (find_package(crowdbake), or set CROWDBAKE_EXECUTABLE)")
  endif()
  get_filename_component(catalog "${catalog}" ABSOLUTE)
  get_filename_component(out "${arg_OUTPUT_DIR}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  set(manifest "${out}/roster.json")
  if(arg_MANIFEST)
    get_filename_component(manifest "${arg_MANIFEST}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  endif()
  set(depfile "${CMAKE_CURRENT_BINARY_DIR}/${target}.roster.d")
  add_custom_command(
    OUTPUT "${manifest}"
    COMMAND "${exe}" bake "${catalog}" --out-dir "${out}" --manifest "${manifest}" --depfile "${depfile}"
            --depfile-manifest-only -q
            ${arg_OPTIONS}
    DEPENDS "${catalog}"
    DEPFILE "${depfile}"
    COMMENT "crowdbake: baking ${catalog}"
    VERBATIM)
  add_custom_target(${target} ALL DEPENDS "${manifest}")
  set_property(TARGET ${target} PROPERTY CROWDBAKE_MANIFEST "${manifest}")
endfunction()
