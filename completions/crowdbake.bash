# bash completion for crowdbake (installed as share/bash-completion/completions/crowdbake).
# Each command's options are those of its --help; tests/install/test_install.c keeps them in step with
# the command's own option tables.

_crowdbake_options()
{
    local limits="--max-joints --max-frames --max-accessor-count --max-file-size --max-palette-size"
    local output="-q --quiet -v --verbose" # every command's (cli/cli_output.c)
    case $1 in
    bake) echo "-o --output --format --fps --layout --precision --max-texture-size --root-motion --skin
                --speed-reference --exr-compression --zstd --json $output -j --threads --force --depfile
                --manifest --out-dir --depfile-manifest-only --fit-rows --allow-over-budget --measure-all --plant-feet --row-travel --bone-space --timed-rows --max-error --max-fps --clip --exclude-clip --loop --one-shot --sync --default-state --type --fragment $limits" ;;
    info) echo "--json --fps --skin --plant-feet $output $limits" ;;
    sample) echo "--json --fps --clip --frame --skin --root-motion $output $limits" ;;
    inspect) echo "--json --clip --frame --no-verify $output" ;;
    verify) echo "--json --clip --exclude-clip --max-error --random --skin $output $limits" ;;
    preview) echo "-o --output --skin --cell --columns $output $limits" ;;
    vat) echo "-o --output --fps --max-texture-size --root-motion --skin --exr-compression --json --clip --exclude-clip
                --like $output $limits" ;;
    report) echo "--json --markdown --html --no-fail -j --target --out-dir $output" ;;
    roster) echo "merge -o --output -q --quiet" ;;
    view) echo "--port --open --cache --model $output $limits" ;;
    mesh) echo "-o --output --palette-model --max-influences --quantize --batch --max-quantization-error --fps --skin
                --vertex-id-uv --skin-texture --json --type --lod $output $limits" ;;
    esac
}

_crowdbake()
{
    local cur prev words cword
    if declare -F _init_completion >/dev/null; then
        _init_completion || return
    else
        cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]} words=("${COMP_WORDS[@]}") cword=$COMP_CWORD
    fi
    local commands="info sample bake inspect verify preview vat report roster mesh view"
    if [[ $cword -eq 1 ]]; then
        COMPREPLY=($(compgen -W "$commands help --help --version -V" -- "$cur"))
        return
    fi
    if [[ $cword -eq 2 && ${words[1]} == help ]]; then
        COMPREPLY=($(compgen -W "$commands" -- "$cur"))
        return
    fi
    case $prev in
    --layout) COMPREPLY=($(compgen -W "mat4 affine qpos" -- "$cur")); return ;;
    --precision) COMPREPLY=($(compgen -W "float half u16" -- "$cur")); return ;;
    --format) COMPREPLY=($(compgen -W "pal exr ktx2 babylon pal,exr pal,exr,ktx2 pal,babylon" -- "$cur")); return ;;
    --max-influences) COMPREPLY=($(compgen -W "1 2 4" -- "$cur")); return ;;
    --root-motion) COMPREPLY=($(compgen -W "keep in-place loops-in-place" -- "$cur")); return ;;
    --bone-space) COMPREPLY=($(compgen -W "global local" -- "$cur")); return ;;
    --timed-rows) COMPREPLY=($(compgen -W "auto on off" -- "$cur")); return ;;
    --exr-compression) COMPREPLY=($(compgen -W "none rle zips zip piz" -- "$cur")); return ;;
    --fps) COMPREPLY=($(compgen -W "24 30 60 auto" -- "$cur")); return ;;
    -o|--output|--depfile|--manifest|--html|--fragment) COMPREPLY=($(compgen -f -- "$cur")); return ;;
    --out-dir|--cache) COMPREPLY=($(compgen -d -- "$cur")); return ;;
    esac
    if [[ $cur == -* ]]; then
        COMPREPLY=($(compgen -W "$(_crowdbake_options "${words[1]}") --help" -- "$cur"))
    else
        COMPREPLY=($(compgen -f -X '!*.@(glb|gltf|pal|exr|ktx2|json|toml|fragment)' -- "$cur") $(compgen -d -- "$cur"))
    fi
}
complete -F _crowdbake crowdbake
