# Stage: keyframe interpolation and animated shots (Dobashi 2012 §5.2, §6; Figs. 13, 15).
# Per frame: `interpolate` (inputs: ONLY the fit params.yaml of the keyframes the frame depends on; params:
# ONLY those keyframes' settings), then `render_frame` (forward renderer, one job per frame: parallel and
# cluster-friendly). So editing one keyframe reruns only the frames of its adjacent segments.
# `phase: mie_blend` frames also take the point-to-point Mie and HG solutions of their sun (rule `point_scatter`
# of the Mie stage), keyed by the frame's sun rounded to `mie_sun_step` degrees, which is known from the config
# alone: frames whose suns round alike share one solution job in the DAG.
# Per shot: `animation` (mp4, or gif without an encoder) and a filmstrip.
from natscene.keyframes.animation import animation_suffix as _anim_suffix
from natscene.keyframes.shot import bracket as _shot_bracket
from natscene.keyframes.shot import camera_neighbours as _shot_camera_neighbours
from natscene.keyframes.shot import frame_sun as _shot_frame_sun
from natscene.keyframes.shot import frame_t as _shot_frame_t
from natscene.keyframes.shot import quantised_sun as _shot_quantised_sun
from natscene.keyframes.shot import sun_key as _shot_sun_key
from natscene.keyframes.shot import resolve_keyframe as _shot_resolve_keyframe
from natscene.keyframes.shot import validate_shot as _validate_shot

for _shot_name, _shot_entry in config.get("shots", {}).items():
    _validate_shot(_shot_name, _shot_entry, config)

localrules: interpolate, animation  # light bookkeeping: on a cluster they run on the submitting host


SHOT_ANIMATION_SUFFIX = _anim_suffix()  # ".mp4" where imageio-ffmpeg finds ffmpeg, else ".gif"


def _shot_cfg(wc):
    if wc.shot not in config.get("shots", {}):
        raise ValueError(f"shot {wc.shot!r} is not in config 'shots'")
    shot = config["shots"][wc.shot]
    frame = getattr(wc, "frame", None)
    if frame is not None and int(frame) >= shot["frames"]:
        raise ValueError(f"frame {wc.frame} is past the last frame of shot {wc.shot!r} ({shot['frames'] - 1})")
    return shot


def _shot_keys(wc):
    """The resolved keyframes (config only) this frame depends on, in frame order."""
    shot = _shot_cfg(wc)
    keys = [_shot_resolve_keyframe(wc.shot, i, shot["keyframes"][i], config)
            for i in _shot_bracket(shot, int(wc.frame))]
    for k in keys:
        k["fit_path"] = f"{RESULTS}/fit/{k['fit']}/params.yaml" if k["fit"] else None
        del k["index"]  # the position in the list is not a setting: reordering keyframes reruns nothing
    return keys


def _shot_path_keys(wc):
    """Catmull-Rom only: frame index + camera of the keyframes around the segment."""
    shot = _shot_cfg(wc)
    if shot["camera_path"] != "catmull_rom":
        return []
    return [{"at": k["at"], "camera": k["camera"]}
            for k in (_shot_resolve_keyframe(wc.shot, i, shot["keyframes"][i], config)
                      for i in _shot_camera_neighbours(shot, int(wc.frame)))]


def _shot_volume(wc, name):
    return f"{RESULTS}/volumes/{config['shots'][wc.shot]['volume']}/{name}"


def _shot_mie_sun(wc):
    """`mie_blend`: the `point_scatter` sun key of this frame (its interpolated sun, rounded); else None."""
    shot = _shot_cfg(wc)
    if shot["phase"] != "mie_blend":
        return None
    keys = _shot_keys(wc)
    _, az, el = _shot_frame_sun(keys, _shot_frame_t(int(wc.frame), keys, shot["easing"]))
    return _shot_sun_key(*_shot_quantised_sun(az, el, shot["mie_sun_step"]))


def _shot_frame_inputs(wc):
    ins = {"state": f"{RESULTS}/shots/{wc.shot}/params/{wc.frame}.yaml",
           "density": _shot_volume(wc, "density.vol"), "meta": _shot_volume(wc, "meta.yaml")}
    sun = _shot_mie_sun(wc)
    if sun is not None:
        shot = config["shots"][wc.shot]
        sfx = f"-{shot['mie_table']}" if shot["mie_table"] else ""
        base = f"{RESULTS}/mie/pointcloud/{shot['volume']}/{sun}"
        ins.update(table=_mie_table_path(shot["mie_table"]), mie=f"{base}/mie{sfx}/solution.npz",
                   hg=f"{base}/hg{sfx}/solution.npz")
    return ins


_MIE_MARCH_KEYS = ("mie_scale", "iso_scale", "step_voxels", "sun_step_voxels", "field_smooth")
_FRAME_KEYS = ("resolution", "render", "sky", "denoise", "denoiser", "phase", "mie_table", "mie_sun_step")


def _shot_frame_settings(wc):
    """The shot's settings a frame depends on (not its keyframes: those reach the frame through its state)."""
    shot = _shot_cfg(wc)
    return {k: shot[k] for k in _FRAME_KEYS}


rule interpolate:
    output:
        f"{RESULTS}/shots/{{shot}}/params/{{frame}}.yaml",
    input:
        lambda wc: [k["fit_path"] for k in _shot_keys(wc) if k["fit_path"]],
    wildcard_constraints:
        shot=r"[^/]+",
        frame=r"\d{4}",
    params:
        keyframes=_shot_keys,
        path_keys=_shot_path_keys,
        easing=lambda wc: config["shots"][wc.shot]["easing"],
        camera_path=lambda wc: config["shots"][wc.shot]["camera_path"],
        code=script_fingerprint("interpolate.py"),
    log:
        f"{RESULTS}/logs/shots/{{shot}}/interpolate.{{frame}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/interpolate/shots/{{shot}}/interpolate.{{frame}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("interpolate"),
    script:
        script_path("interpolate.py")


rule render_frame:
    output:
        exr=f"{RESULTS}/shots/{{shot}}/frames/{{frame}}.exr",
        raw=f"{RESULTS}/shots/{{shot}}/frames/{{frame}}.raw.exr",
    input:
        unpack(_shot_frame_inputs),
    wildcard_constraints:
        shot=r"[^/]+",
        frame=r"\d{4}",
    params:
        shot=_shot_frame_settings,
        mie_sun=_shot_mie_sun,
        # only the final-pass settings the Mie/HG ratio uses (not the demo's light colour or sky)
        mie_render=lambda wc: {k: config["mie"]["render"][k] for k in _MIE_MARCH_KEYS} if _shot_mie_sun(wc) else {},
        mie_sigma_t=lambda wc: config["mie"]["solver"]["sigma_t"] if _shot_mie_sun(wc) else None,
        code=script_fingerprint("render_frame.py"),
    log:
        f"{RESULTS}/logs/shots/{{shot}}/render_frame.{{frame}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/render_frame/shots/{{shot}}/render_frame.{{frame}}.tsv",
    threads: config["threads"]
    resources:
        mem_mb=estimated_mem_mb("render_frame"),
        runtime=lambda wc: 30 if config["shots"][wc.shot]["resolution"][0] * config["shots"][wc.shot]["resolution"][1] <= 640 * 480 else 120,
    script:
        script_path("render_frame.py")


# The frame's PNG (a preview at the shot's fixed exposure): its own rule, so a new exposure redraws the PNGs and
# the animation and renders no frame.
rule frame_preview:
    output:
        png=f"{RESULTS}/shots/{{shot}}/frames/{{frame}}.png",
    input:
        exr=f"{RESULTS}/shots/{{shot}}/frames/{{frame}}.exr",
    wildcard_constraints:
        shot=r"[^/]+",
        frame=r"\d{4}",
    params:
        exposure=lambda wc: config["shots"][wc.shot]["exposure"],
        code=script_fingerprint("exr_preview.py"),
    log:
        f"{RESULTS}/logs/shots/{{shot}}/frame_preview.{{frame}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/frame_preview/shots/{{shot}}/frame_preview.{{frame}}.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("frame_preview"),
    script:
        script_path("exr_preview.py")


rule animation:
    output:
        animation=f"{RESULTS}/shots/{{shot}}/animation{SHOT_ANIMATION_SUFFIX}",
    input:
        lambda wc: [f"{RESULTS}/shots/{wc.shot}/frames/{f:04d}.png" for f in range(config["shots"][wc.shot]["frames"])],
    wildcard_constraints:
        shot=r"[^/]+",
    params:
        fps=lambda wc: config["shots"][wc.shot]["fps"],
        code=script_fingerprint("animation.py"),
    log:
        f"{RESULTS}/logs/shots/{{shot}}/animation.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/animation/shots/{{shot}}/animation.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("animation"),
    script:
        script_path("animation.py")


def _filmstrip_frames(wc):
    """The frame PNGs the strip shows: `filmstrip.count` of them spread evenly, first and last included."""
    from natscene.keyframes.animation import strip_indices
    shot = config["shots"][wc.shot]
    return [f"{RESULTS}/shots/{wc.shot}/frames/{f:04d}.png"
            for f in strip_indices(shot["frames"], shot["filmstrip"]["count"])]


# The filmstrip: its own rule, so its layout (`filmstrip.count`, `filmstrip.height`) redraws the strip alone.
rule filmstrip:
    output:
        filmstrip=f"{RESULTS}/shots/{{shot}}/filmstrip.png",
    input:
        _filmstrip_frames,
    wildcard_constraints:
        shot=r"[^/]+",
    params:
        height=lambda wc: config["shots"][wc.shot]["filmstrip"]["height"],
        code=script_fingerprint("filmstrip.py"),
    log:
        f"{RESULTS}/logs/shots/{{shot}}/filmstrip.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/filmstrip/shots/{{shot}}/filmstrip.tsv",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("filmstrip"),
    script:
        script_path("filmstrip.py")


for _shot_name in config.get("shots", {}):
    ALL_TARGETS.extend([f"{RESULTS}/shots/{_shot_name}/animation{SHOT_ANIMATION_SUFFIX}",
                        f"{RESULTS}/shots/{_shot_name}/filmstrip.png"])
