"""Bazel rules for crowdbake: bone-matrix palettes for GPU crowds, one action per animal type.

    load("//bazel:crowdbake.bzl", "crowdbake_bake", "crowdbake_roster")

crowdbake enters as files built by `make bundle` (build/bundle: bin/crowdbake and the shared
libraries it finds through $ORIGIN), wrapped in a filegroup and passed as the `crowdbake`
attribute: Bazel needs no C/C++ toolchain and downloads nothing, and every action's inputs are
complete, so it runs the same on a remote executor that has libc alone. docs/bazel.md says how
to point these rules at a Remote Execution API cache or executor.
"""

def _tool(ctx):
    """The crowdbake executable among the bundle's files, and all of them (its libraries)."""
    files = ctx.files.crowdbake
    exe = [f for f in files if f.basename == "crowdbake" and f.dirname.endswith("bin")]
    if len(exe) != 1:
        fail("%s: crowdbake = %s must hold bin/crowdbake of `make bundle` (with its lib/ folder)" %
             (ctx.label, ctx.attr.crowdbake.label))
    return exe[0], files

_FORMAT_EXTENSIONS = {"pal": "pal", "exr": "exr", "babylon": "bvat.json"}

def _outputs(ctx, folder, stem):
    outs = []
    for fmt in ctx.attr.formats:
        if fmt not in _FORMAT_EXTENSIONS:
            fail("%s: formats holds '%s'; crowdbake writes pal, exr and babylon" % (ctx.label, fmt))
        outs.append(ctx.actions.declare_file("%s/%s.%s" % (folder, stem, _FORMAT_EXTENSIONS[fmt])))
    return outs

_COMMON = {
    "crowdbake": attr.label(mandatory = True, allow_files = True, cfg = "exec",
                            doc = "a filegroup of `make bundle`'s files: bin/crowdbake and lib/*"),
    "formats": attr.string_list(default = ["pal"], doc = "pal, exr and/or babylon"),
    "bake_args": attr.string_list(doc = "more `crowdbake bake` options (--layout qpos, --precision u16, ...)"),
}

def _type_impl(ctx):
    exe, tool_files = _tool(ctx)
    folder = ctx.attr.roster
    outs = _outputs(ctx, folder, ctx.attr.type)
    fragment = ctx.actions.declare_file("%s/%s.fragment" % (folder, ctx.attr.type))
    out_dir = fragment.dirname
    args = ctx.actions.args()
    args.add_all(["bake", ctx.file.catalog.path, "--type", ctx.attr.type, "--out-dir", out_dir,
                  "--fragment", fragment.path, "-q", "-j", "1"])
    if ctx.attr.formats != ["pal"]:
        args.add_all(["--format", ",".join(ctx.attr.formats)])
    args.add_all(ctx.attr.bake_args)
    ctx.actions.run(
        executable = exe,
        tools = tool_files,
        arguments = [args],
        inputs = [ctx.file.catalog] + ctx.files.models,
        outputs = outs + [fragment],
        mnemonic = "CrowdbakeType",
        progress_message = "crowdbake: baking %s (%s)" % (ctx.attr.type, ctx.label),
    )
    return [DefaultInfo(files = depset(outs + [fragment]))]

crowdbake_type = rule(
    implementation = _type_impl,
    doc = "One animal type of a catalog: its palette and its manifest fragment (crowdbake bake --type).",
    attrs = dict(_COMMON, **{
        "catalog": attr.label(mandatory = True, allow_single_file = [".toml"]),
        "type": attr.string(mandatory = True, doc = "the [animal.NAME] to bake"),
        "models": attr.label_list(allow_files = True, doc = "the type's model, LODs and their external files"),
        "roster": attr.string(mandatory = True, doc = "the folder of the roster's outputs"),
    }),
)

def _merge_impl(ctx):
    exe, tool_files = _tool(ctx)
    manifest = ctx.actions.declare_file("%s/roster.json" % ctx.attr.roster)
    fragments = [f for f in ctx.files.types if f.extension == "fragment"]
    args = ctx.actions.args()
    args.add_all(["roster", "merge", "-q", "-o", manifest.path])
    args.add_all(fragments)
    ctx.actions.run(
        executable = exe,
        tools = tool_files,
        arguments = [args],
        inputs = [ctx.file.catalog] + fragments,
        outputs = [manifest],
        mnemonic = "CrowdbakeMerge",
        progress_message = "crowdbake: merging %d types into %s" % (len(fragments), manifest.short_path),
    )
    return [DefaultInfo(files = depset([manifest] + ctx.files.types))]

_crowdbake_merge = rule(
    implementation = _merge_impl,
    attrs = {
        "crowdbake": _COMMON["crowdbake"],
        "catalog": attr.label(mandatory = True, allow_single_file = [".toml"]),
        "types": attr.label_list(mandatory = True),
        "roster": attr.string(mandatory = True),
    },
)

def _report_impl(ctx):
    exe, tool_files = _tool(ctx)
    report = ctx.actions.declare_file(ctx.label.name + ".json")
    scratch = report.dirname + "/" + ctx.label.name + ".bake"
    cmd = "set -e; \"$1\" report \"$2\" --json --no-fail -q -j 1 --out-dir \"$3\" > \"$4\""
    ctx.actions.run_shell(
        command = cmd,
        arguments = [exe.path, ctx.file.catalog.path, scratch, report.path],
        tools = tool_files,
        inputs = [ctx.file.catalog] + ctx.files.models,
        outputs = [report],
        mnemonic = "CrowdbakeReport",
        progress_message = "crowdbake: the VRAM report of %s" % ctx.file.catalog.short_path,
    )
    return [DefaultInfo(files = depset([report]))]

_crowdbake_report = rule(
    implementation = _report_impl,
    attrs = {
        "crowdbake": _COMMON["crowdbake"],
        "catalog": attr.label(mandatory = True, allow_single_file = [".toml"]),
        "models": attr.label_list(allow_files = True),
    },
)

def crowdbake_roster(name, catalog, models, crowdbake, formats = ["pal"], bake_args = [], report = True, **kwargs):
    """A catalog's roster: one action per animal type, the merge, and the VRAM report.

    Args:
      name: the roster; its outputs go to the package's NAME/ folder (roster.json, TYPE.pal, ...).
      catalog: the catalog (.toml).
      models: a dict from each [animal.NAME] of the catalog to the files it reads (model, LODs,
        external buffers): a type's action has those inputs alone, so a changed model re-runs
        its type's action and the merge, nothing else.
      crowdbake: a filegroup of `make bundle`'s files (bin/crowdbake and lib/*).
      formats: pal, exr and/or babylon.
      bake_args: more `crowdbake bake` options, for every type.
      report: also NAME_report: `crowdbake report --json` of the roster against its [budget].
      **kwargs: visibility, tags, ... for the targets the macro declares.
    """
    type_targets = []
    for type_name in sorted(models.keys()):
        target = "%s_%s" % (name, type_name)
        crowdbake_type(
            name = target,
            catalog = catalog,
            type = type_name,
            models = models[type_name],
            roster = name,
            crowdbake = crowdbake,
            formats = formats,
            bake_args = bake_args,
            **kwargs
        )
        type_targets.append(":" + target)
    _crowdbake_merge(name = name, catalog = catalog, types = type_targets, roster = name, crowdbake = crowdbake,
                     **kwargs)
    if report:
        all_models = []
        for files in models.values():
            all_models += [f for f in files if f not in all_models]
        _crowdbake_report(name = name + "_report", catalog = catalog, models = all_models, crowdbake = crowdbake,
                          **kwargs)

def _bake_impl(ctx):
    exe, tool_files = _tool(ctx)
    stem = ctx.label.name
    outs = _outputs(ctx, ".", stem)
    first = outs[0]
    args = ctx.actions.args()
    args.add_all(["bake", ctx.file.model.path, "-o", first.path, "-q"])
    if ctx.attr.formats != ["pal"]:
        args.add_all(["--format", ",".join(ctx.attr.formats)])
    args.add_all(ctx.attr.bake_args)
    ctx.actions.run(
        executable = exe,
        tools = tool_files,
        arguments = [args],
        inputs = [ctx.file.model] + ctx.files.data,
        outputs = outs,
        mnemonic = "CrowdbakeBake",
        progress_message = "crowdbake: baking %s" % ctx.file.model.short_path,
    )
    return [DefaultInfo(files = depset(outs))]

crowdbake_bake = rule(
    implementation = _bake_impl,
    doc = "One model's palette: NAME.pal (and NAME.exr / NAME.bvat.json with formats).",
    attrs = dict(_COMMON, **{
        "model": attr.label(mandatory = True, allow_single_file = [".glb", ".gltf"]),
        "data": attr.label_list(allow_files = True, doc = "a .gltf's external buffers and images"),
    }),
)
