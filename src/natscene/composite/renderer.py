"""
Hybrid rendering of the set
===========================

Defines the hybrid rendering of the set (Dong 2007, Ch. 2, §2.3-2.5, Fig. 2.3): shading of the rays of
:mod:`natscene.composite.set_geometry` (the same for every colour mode):

-   :class:`SetRenderer`: traces the set's rays once and shades them in a colour mode.
-   :func:`spectral_coverage`: the fraction of pixels with a non-zero spectral part.
-   :data:`HAZE_MIN`: the in-scattered fraction below which the aerial perspective is not evaluated.

Shading of RGB materials (ground, petals, leaves, stems; Dong: "RGB materials lit in RGB by the RGB value of
every light", the spectral sun converted once, §2.3.3): L = ρ/π · (E_sun·max(n·l, 0)·V + E_sky(n))
+ τ ρ/π · (E_sun·max(−n·l, 0)·V + E_sky(−n)) for a sheet of translucency τ (light through a petal from
behind), E_sky from :class:`natscene.composite.sky_dome.SkyDome`. Every surface sample then takes the
aerial perspective of Dobashi Eq. 3 with the frame's κ_a over its distance
(:func:`natscene.scatter.compose.apply_atmosphere`, the function the cloud frames use), toward the frame's
sky radiance in the ray's direction, so the ground fades into the same horizon haze as the clouds.

Spectral materials (thin films, §2.5) in hybrid mode: R_film(θ_v, λ)·L_env(λ) of what the mirror ray sees
(its RGB radiance upsampled, Fig. 2.3(b)) plus the sun lobe R_film(θ_d, λ)·E_sun(λ)·(e+8)/(8π)(n·h)^e cosθ V,
with Dong's RGB highlight in the RGB part. Their aerial perspective: the spectral part is scaled by the
luminance-weighted transmittance, the in-scattered sky goes to the RGB part (the set's objects are metres
away; the grey factor differs from per-channel e^{−κ t} by < 1e−4 there). Mode ``"rgb"`` shades the films in
RGB instead (the film reflectance tables integrated to RGB under D65): the baseline of the cost benchmark.

Rays that leave the set show the background plate (the shot's cloud frame, rendered from the same camera).

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import time

import numpy as np

from natscene.composite.hybrid import HybridImage
from natscene.composite.set_geometry import (KIND_FILM, KIND_GROUND, KIND_SKY, KIND_SURFACE, Hits, MirrorHits,
                                             SetGeometry)
from natscene.composite.set_spec import SetSpec
from natscene.composite.sky_dome import SkyDome
from natscene.spectral.grid import reflectance_to_rgb
from natscene.spectral.illuminants import d65
from natscene.spectral.thin_film import FilmTable, film_table
from natscene.spectral.upsampling import rgb_to_radiance

__all__ = ["HAZE_MIN", "SetRenderer", "spectral_coverage"]

HAZE_MIN = 1e-4  # in-scattered fraction below which the aerial perspective is not evaluated


class SetRenderer(SetGeometry):
    """Traces the set's rays once (shared geometry, :class:`~natscene.composite.set_geometry.SetGeometry`) and shades
    them in ``hybrid`` or ``rgb`` mode
    (:func:`natscene.composite.full_spectral.render_full_spectral` shades the same rays spectrally).
    ``timing``: seconds in the shared geometry (``geometry``) and in the mode's shading (``shading``)."""

    def __init__(self, spec: SetSpec):
        super().__init__(spec)
        self.tables: list[FilmTable] = [film_table(f.layers, f.substrate, grid=spec.grid,
                                                   angle_step_deg=spec.angle_step_deg) for f in spec.films]
        for t in self.tables:
            t.R = t.R.astype(np.float32)
        g_albedo = spec.ground.texture.mean()[:3] if spec.ground is not None else np.zeros(3)
        self.dome = SkyDome(spec.sky, self.sun_dir, self.sun_rgb, g_albedo)
        self.surface_color = np.array([np.asarray(s.color, np.float32)[:3] for s in spec.surfaces] or
                                      np.zeros((0, 3)), np.float32).reshape(-1, 3)
        self._film_rgb = None

    # ------------------------------------------------------------------------------ materials
    def albedo_rgb(self, h: Hits, sel: np.ndarray, coarse: bool = False) -> np.ndarray:
        """RGB albedo (len(sel), 3) of ground/surface samples ``sel``: filtered texture lookups over their
        footprints (``coarse``: secondary rays, the texture's level ``max_level - 4``)."""
        out = np.zeros((sel.size, 3), np.float32)
        kind, index = h.kind[sel], h.index[sel]
        spec = self.spec
        g = kind == KIND_GROUND
        if g.any() and spec.ground is not None:
            if coarse or h.duv_dx is None or not h.pixels or spec.spp == 1:
                out[g] = self.texture_lookup(spec.ground.texture, h, sel[g], coarse)[:, :3]
            else:
                out[g] = self._ground_per_pixel(h, sel[g])
        for i, s in enumerate(spec.surfaces):
            k = (kind == KIND_SURFACE) & (index == i)
            if k.any():
                out[k] = self.texture_lookup(s.texture, h, sel[k], coarse)[:, :3] if s.texture is not None \
                    else self.surface_color[i]
        return out

    def texture_lookup(self, tex, h: Hits, idx: np.ndarray, coarse: bool = False) -> np.ndarray:
        """Filtered lookup of ``tex`` (any channels) for samples ``idx`` over their footprints (``coarse`` or no
        footprint: the texture's level ``max_level - 4``, for secondary rays)."""
        uv = h.uv[idx]
        if coarse or h.duv_dx is None:
            return tex.trilinear(uv, np.full(uv.shape[0], max(tex.max_level - 4, 0)))
        return tex.filtered(uv, h.duv_dx[idx], h.duv_dy[idx], self.spec.max_aniso)

    def _ground_per_pixel(self, h: Hits, gs: np.ndarray) -> np.ndarray:
        """Ground albedo of samples ``gs`` filtered once per pixel where every sample of the pixel sees the
        ground (multisample-style: one lookup at the samples' mean (u, v) over the whole pixel's footprint,
        k = ceil(sqrt(spp)) sample spacings), per sample elsewhere (pixels at an object's edge)."""
        P, spp = h.pixels, self.spec.spp
        tex = self.spec.ground.texture
        pix = gs % P
        full = np.bincount(pix, minlength=P) == spp
        out = np.empty((gs.size, 3), np.float32)
        per = full[pix]
        if per.any():
            fp = np.flatnonzero(full)
            w = np.float64(1.0 / spp)
            g_in = gs[per]
            p_in = pix[per]
            uv = np.stack([np.bincount(p_in, weights=h.uv[g_in, c], minlength=P)[fp] for c in (0, 1)], -1) * w
            k = float(np.ceil(np.sqrt(spp)))
            dx = np.stack([np.bincount(p_in, weights=h.duv_dx[g_in, c], minlength=P)[fp] for c in (0, 1)], -1) * w * k
            dy = np.stack([np.bincount(p_in, weights=h.duv_dy[g_in, c], minlength=P)[fp] for c in (0, 1)], -1) * w * k
            vals = tex.filtered(uv, dx, dy, self.spec.max_aniso)[:, :3]
            slot = np.full(P, -1, np.int64)
            slot[fp] = np.arange(fp.size)
            out[per] = vals[slot[p_in]]
        if (~per).any():
            e = gs[~per]
            out[~per] = tex.filtered(h.uv[e], h.duv_dx[e], h.duv_dy[e], self.spec.max_aniso)[:, :3]
        return out

    def irradiance_rgb(self, h: Hits, sel: np.ndarray) -> np.ndarray:
        """Irradiance (len(sel), 3) on the front side plus τ times the back side's (sun and sky dome)."""
        E = self.sky_irradiance(h, sel, self.dome.irradiance)
        E += self.sun_rgb[None] * h.sun_front[sel, None]
        # τ of the samples (the translucency table's last entry, 0, for all but RGB surfaces)
        tr = self.translucency[np.where(h.kind[sel] == KIND_SURFACE, h.index[sel], -1)]
        back = np.flatnonzero(tr > 0)
        if back.size:
            sb = sel[back]
            Eb = self.sun_rgb[None] * h.sun_back[sb, None] + self.dome.irradiance(-h.n[sb])
            E[back] += tr[back, None] * Eb
        return E

    @staticmethod
    def sky_irradiance(h: Hits, sel: np.ndarray, irradiance) -> np.ndarray:
        """``irradiance(normals)`` (the sky dome's, RGB or spectral) of samples ``sel``: one evaluation for all
        ground samples (the flat ground's normal is up), one per mesh sample."""
        up = irradiance(np.array([[0.0, 1.0, 0.0]]))
        out = np.empty((sel.size, up.shape[-1]), np.float32)
        out[:] = up
        mesh = np.flatnonzero(h.kind[sel] != KIND_GROUND)
        out[mesh] = irradiance(h.n[sel[mesh]])
        return out

    def transmittance(self, h: Hits, sel: np.ndarray) -> np.ndarray:
        """e^{-κ_a t / d_ref} (len(sel), 3) of Dobashi Eq. 3 over the samples' distances (1 without air)."""
        at = self.spec.atmosphere
        if at is None:
            return np.ones((sel.size, 3), np.float32)
        tc = (h.t[sel] / at.reference_distance).astype(np.float32)
        return np.exp(-np.asarray(at.kappa, np.float32)[None] * tc[:, None])

    def hazy(self, h: Hits, sel: np.ndarray) -> np.ndarray:
        """Which samples ``sel`` are far enough for the haze to matter: 1 - e^{-κ t / d_ref} >= ``HAZE_MIN`` in
        some channel (nearer ones keep their radiance, changed by less than 1e-4 of the sky-minus-surface
        difference)."""
        at = self.spec.atmosphere
        return h.t[sel] * float(np.max(at.kappa)) / at.reference_distance >= HAZE_MIN

    def aerial(self, L: np.ndarray, h: Hits, sel: np.ndarray) -> np.ndarray:
        """Dobashi Eq. 3 over the samples ``sel``: L e^{-κ t} + (1 - e^{-κ t}) L_sky(direction)."""
        at = self.spec.atmosphere
        if at is None:
            return L
        from natscene.scatter.compose import apply_atmosphere
        far = self.hazy(h, sel)
        if far.any():
            f = sel[far]
            L[far] = apply_atmosphere(L[far], (h.t[f] / at.reference_distance).astype(np.float32), at.kappa,
                                      self.dome.radiance(h.dirs[f]))
        return L

    def radiance_rgb(self, h: Hits, sel: np.ndarray, coarse: bool = False) -> np.ndarray:
        """RGB radiance arriving along rays ``sel`` that hit ground or RGB surfaces (aerial perspective included)."""
        L = self.albedo_rgb(h, sel, coarse) / np.float32(np.pi) * self.irradiance_rgb(h, sel)
        return self.aerial(L, h, sel)

    def gather_mirror_rgb(self, mh: MirrorHits) -> np.ndarray:
        """RGB radiance along the mirror rays of film samples: set geometry or the sky (a film seen in a film
        shows the sky behind it, every mode)."""
        h = mh.hits
        out = self.dome.radiance(h.dirs).astype(np.float32)
        surf = np.flatnonzero((h.kind == KIND_GROUND) | (h.kind == KIND_SURFACE))
        if surf.size:
            out[surf] = self.radiance_rgb(h, surf, coarse=True)
        return out

    def lobe(self, i: int, nh: np.ndarray, sun_cos: np.ndarray) -> np.ndarray:
        """Normalised Blinn-Phong sun lobe (e+8)/(8π) (n·h)^e cosθ V of film ``i``."""
        e = self.spec.films[i].gloss
        return ((e + 8) / (8 * np.pi) * nh ** e * sun_cos).astype(np.float32)

    def film_spectra(self, h: Hits, fm: np.ndarray, mh: MirrorHits, L_env: np.ndarray,
                     highlight_spectra=None) -> tuple[np.ndarray, np.ndarray]:
        """Spectral radiance (F, N) of film samples ``fm``: the tabulated film reflectance times the environment
        spectrum ``L_env`` the mirror ray brings, plus the sun's SPD through the glossy lobe (Eqs. 1.14-1.25
        tables, §2.2). ``highlight_spectra[i]`` (N,) is added to film i's sun reflectance (the full-spectral
        mode's upsampled highlight; the hybrid keeps the highlight in RGB). Also returns the lobe (F,)."""
        F = fm.size
        S = np.zeros((F, self.spec.grid.size), np.float32)
        lobe = np.zeros(F, np.float32)
        idx = h.index[fm]
        sun_cos = h.sun_front[fm]
        for i in range(len(self.spec.films)):
            k = idx == i
            if not k.any():
                continue
            tab = self.tables[i]
            lobe[k] = self.lobe(i, mh.nh[k], sun_cos[k])
            sun_refl = tab.reflectance(mh.cos_d[k])
            if highlight_spectra is not None:
                sun_refl = sun_refl + highlight_spectra[i][None]
            S[k] = tab.reflectance(mh.cos_v[k]) * L_env[k] + sun_refl * (self.sun_S[None] * lobe[k][:, None])
        return S, lobe

    def highlight_rgb(self, h: Hits, fm: np.ndarray, lobe: np.ndarray) -> np.ndarray:
        """Dong's RGB highlight (F, 3): highlight_rgb · E_sun,rgb · lobe."""
        hl = np.array([f.highlight_rgb for f in self.spec.films], np.float32).reshape(-1, 3)
        return hl[h.index[fm]] * self.sun_rgb[None] * lobe[:, None]

    def film_rgb_tables(self) -> list[np.ndarray]:
        """Film reflectance per table angle integrated to linear RGB under D65 (the RGB baseline)."""
        if self._film_rgb is None:
            ill = d65(self.spec.grid)
            self._film_rgb = [reflectance_to_rgb(t.R.astype(np.float64), ill, self.spec.grid).astype(np.float32)
                              for t in self.tables]
        return self._film_rgb

    def shade_film_rgb(self, h: Hits, fm: np.ndarray, mh: MirrorHits) -> np.ndarray:
        """Films shaded in RGB: R_rgb(θ_v)·L_env,rgb + (R_rgb(θ_d) + highlight)·E_sun,rgb·lobe."""
        env = self.gather_mirror_rgb(mh)
        out = np.zeros((fm.size, 3), np.float32)
        idx = h.index[fm]
        tabs = self.film_rgb_tables()
        for i in range(len(self.spec.films)):
            k = idx == i
            if not k.any():
                continue
            tab = self.tables[i]
            R = tabs[i]
            lobe = self.lobe(i, mh.nh[k], h.sun_front[fm][k])
            Rv = _interp_rows(tab, R, mh.cos_v[k])
            Rd = _interp_rows(tab, R, mh.cos_d[k])
            hl = np.asarray(self.spec.films[i].highlight_rgb, np.float32)
            out[k] = Rv * env[k] + (Rd + hl[None]) * self.sun_rgb[None] * lobe[:, None]
        return out

    # ------------------------------------------------------------------------------ renders
    def render_hybrid(self, film_mode: str = "spectral") -> HybridImage:
        """Dong §2.3-2.4: the RGB part for RGB materials, the spectral part only on the film samples
        (``film_mode="rgb"``: films in RGB too, the spectral part stays empty)."""
        spec = self.spec
        H, W, N = spec.camera.height, spec.camera.width, spec.grid.size
        self.timing = {"geometry": 0.0, "shading": 0.0}
        t_start = time.perf_counter()
        spp = spec.spp
        rgb = np.zeros((H * W, 3), np.float32)
        S = np.zeros((H * W, N), np.float32)
        A = np.zeros(H * W, np.float32)
        has_s = np.zeros(H * W, bool)
        plate = spec.plate.reshape(-1, 3).astype(np.float32)
        origin = np.asarray(spec.camera.position, np.float64)
        for sl, dirs, ddx, ddy in self.blocks():
            h = self.trace(origin, dirs, ddx, ddy, pixels=sl.stop - sl.start)
            n = sl.stop - sl.start
            out = np.zeros((h.kind.size, 3), np.float32)
            bg = h.kind == KIND_SKY
            bg_i = np.flatnonzero(bg)
            out[bg_i] = plate[sl.start + bg_i % n]
            rm = np.flatnonzero((h.kind == KIND_GROUND) | (h.kind == KIND_SURFACE))
            out[rm] = self.radiance_rgb(h, rm)
            fm = np.flatnonzero(h.kind == KIND_FILM)
            if fm.size:
                mh = self.mirror(h, fm)
                T = self.transmittance(h, fm)
                sky_in = (1 - T) * self.dome.radiance(h.dirs[fm])
                if film_mode == "rgb":
                    out[fm] = self.shade_film_rgb(h, fm, mh) * T + sky_in
                else:
                    env = self.gather_mirror_rgb(mh)
                    L_env = rgb_to_radiance(env, spec.grid, spec.upsampling).astype(np.float32)
                    s, lobe = self.film_spectra(h, fm, mh, L_env)
                    Tg = T @ np.array([0.2126, 0.7152, 0.0722], np.float32)
                    out[fm] = self.highlight_rgb(h, fm, lobe) * T + sky_in
                    s *= Tg[:, None]
                    for j in range(spp):  # scatter the film samples' spectra into their pixels
                        k = (fm >= j * n) & (fm < (j + 1) * n)
                        px = sl.start + fm[k] - j * n
                        np.add.at(S, px, s[k])
                        has_s[px] = True
            rgb[sl] = out.reshape(spp, n, 3).sum(0)
            A[sl] = (~bg).reshape(spp, n).sum(0)
        w = np.float32(1.0 / spp)
        S[has_s] *= w  # the spectral part is sparse: only the film objects' pixels are touched
        out = HybridImage((rgb * w).reshape(H, W, 3), S.reshape(H, W, N), (A * w).reshape(H, W), spec.grid,
                          has_s.reshape(H, W))
        self.timing["shading"] = time.perf_counter() - t_start - self.timing["geometry"]
        return out


def _interp_rows(tab: FilmTable, R: np.ndarray, cos_theta: np.ndarray) -> np.ndarray:
    """Rows of a per-angle table ``R`` (n_angles, C) interpolated like :meth:`FilmTable.reflectance`."""
    th = np.degrees(np.arccos(np.clip(cos_theta, 0.0, 1.0)))
    ang = np.asarray(tab.angles_deg, np.float64)
    x = np.interp(th, ang, np.arange(ang.size))
    i0 = np.clip(np.floor(x).astype(int), 0, ang.size - 2)
    f = (x - i0).astype(np.float32)[:, None]
    return R[i0] * (1 - f) + R[i0 + 1] * f


def spectral_coverage(hybrid: HybridImage) -> float:
    """Fraction of pixels with a non-zero spectral part."""
    if hybrid.mask is not None:
        return float(np.mean(hybrid.mask & np.any(hybrid.spectral != 0, axis=-1)))
    return float(np.mean(np.any(hybrid.spectral != 0, axis=-1)))
