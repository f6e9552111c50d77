"""Rule `interpolate`: the parameter set, sun and camera of one frame of a shot, from its one or two keyframes."""
from natscene import io
from natscene.keyframes.shot import frame_state, keyframe_params
from natscene.runner import run


def main(snakemake, log):
    par = snakemake.params
    frame = int(snakemake.wildcards.frame)
    keys = []
    for k in par.keyframes:
        fitted = io.read_yaml(k["fit_path"]) if k.get("fit_path") else None
        source = k["fit_path"] or f"config key 'shots.{snakemake.wildcards.shot}.keyframes' (at {k['at']})"
        keys.append({**k, "params": keyframe_params(k, fitted, source)})
    state = frame_state(frame, keys, easing=par.easing, camera_path=par.camera_path,
                        path_keys=list(par.path_keys) or None)
    state = {"shot": snakemake.wildcards.shot, **state,
             "sources": [{"at": k["at"], "fit": k["fit"], "explicit": sorted((k.get("params") or {}).keys())}
                         for k in par.keyframes]}
    io.write_yaml(snakemake.output[0], state)
    p = state["params"]
    log.info(f"frame {frame}: keyframes {state['keyframes']}, t={state['t']:.3f}, L_in={p['L_in']:.3g}, "
             f"c_in={[round(c, 3) for c in p['c_in']]}, sun az/el {state['sun']['azimuth']:.1f}/"
             f"{state['sun']['elevation']:.1f}")


run(snakemake, main)
