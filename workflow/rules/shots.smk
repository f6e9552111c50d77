# Stage: keyframe interpolation and animated shots (Dobashi 2012 §5.2, §6; Figs. 13, 15).
# Per frame: `interpolate` (inputs: ONLY the fit params.yaml of the keyframes the frame depends on; params:
# ONLY those keyframes' settings), then `render_frame` (forward renderer, one job per frame: parallel and
# cluster-friendly). So editing one keyframe reruns only the frames of its adjacent segments.
# Per shot: `animation` (mp4, or gif without an encoder) and a filmstrip.
from natscene.keyframes.animation import animation_suffix as _anim_suffix
from natscene.keyframes.shot import bracket as _shot_bracket
from natscene.keyframes.shot import camera_neighbours as _shot_camera_neighbours
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
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("interpolate"),
    script:
        script_path("interpolate.py")


rule render_frame:
    output:
        exr=f"{RESULTS}/shots/{{shot}}/frames/{{frame}}.exr",
        png=f"{RESULTS}/shots/{{shot}}/frames/{{frame}}.png",
    input:
        state=f"{RESULTS}/shots/{{shot}}/params/{{frame}}.yaml",
        density=lambda wc: _shot_volume(wc, "density.vol"),
        meta=lambda wc: _shot_volume(wc, "meta.yaml"),
    wildcard_constraints:
        shot=r"[^/]+",
        frame=r"\d{4}",
    params:
        resolution=lambda wc: config["shots"][wc.shot]["resolution"],
        render=lambda wc: config["shots"][wc.shot]["render"],
        sky=lambda wc: config["shots"][wc.shot]["sky"],
        exposure=lambda wc: config["shots"][wc.shot]["exposure"],
        code=script_fingerprint("render_frame.py"),
    log:
        f"{RESULTS}/logs/shots/{{shot}}/render_frame.{{frame}}.log",
    threads: config["threads"]
    resources:
        mem_mb=estimated_mem_mb("render_frame"),
        runtime=30,
    script:
        script_path("render_frame.py")


rule animation:
    output:
        animation=f"{RESULTS}/shots/{{shot}}/animation{SHOT_ANIMATION_SUFFIX}",
        filmstrip=f"{RESULTS}/shots/{{shot}}/filmstrip.png",
    input:
        lambda wc: [f"{RESULTS}/shots/{wc.shot}/frames/{f:04d}.png" for f in range(config["shots"][wc.shot]["frames"])],
    wildcard_constraints:
        shot=r"[^/]+",
    params:
        fps=lambda wc: config["shots"][wc.shot]["fps"],
        filmstrip=lambda wc: config["shots"][wc.shot]["filmstrip"],
        code=script_fingerprint("animation.py"),
    log:
        f"{RESULTS}/logs/shots/{{shot}}/animation.log",
    threads: 1
    resources:
        mem_mb=estimated_mem_mb("animation"),
    script:
        script_path("animation.py")


for _shot_name in config.get("shots", {}):
    ALL_TARGETS.extend([f"{RESULTS}/shots/{_shot_name}/animation{SHOT_ANIMATION_SUFFIX}",
                        f"{RESULTS}/shots/{_shot_name}/filmstrip.png"])
