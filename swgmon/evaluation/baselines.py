"""The baselines a reviewer expects beside the monitor (issue 83): two charts on the same
health features (:mod:`learn.inputs.health`), commissioned on the same windows, scored
at the same false-alarm rate (:func:`.statistics.matched_threshold`).

* :class:`RegressionMEWMA`: a normal-behaviour model, each feature regressed on the
  operating variables (per duty point, a quadratic in the temperature reading; scikit-
  learn's ``Ridge``), its residuals charted by a multivariate EWMA (Lowry, Woodall, Champ
  and Rigdon, Technometrics 34(1):46, 1992): z_t = λ r_t + (1 − λ) z_(t−1), statistic
  z_t' Σ_z⁻¹ z_t with Σ_z = λ / (2 − λ) Σ_r, the residuals' covariance shrunk by Ledoit
  and Wolf (scikit-learn's ``LedoitWolf``). The wind-turbine practice of the REAL-DAY
  background (Tautz-Weinert and Watson 2016).
* :class:`PCAChart`: each feature standardised per duty point on commissioning, then
  scikit-learn's ``PCA`` keeping ``variance`` of it: Hotelling's T² on the kept components
  and the squared prediction error (SPE, Q) of the rest (Jackson and Mudholkar,
  Technometrics 21(3):341, 1979), each over its 99.9th percentile on commissioning; the
  statistic is the larger ratio.

Both take windows as (features, duty point, temperature reading); a missing reading
(NaN, or a stream without one) is replaced by commissioning's mean. Neither knows the
monitor's laws: no friction law, no drift model, no maintenance log.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import allowed

__all__ = ["BaselineConfig", "PCAChart", "RegressionMEWMA"]


@dataclass
class BaselineConfig:
    """Settings of the two baselines (:mod:`.baselines`).

    Attributes
    ----------
    lam : float
        λ of the MEWMA, in (0, 1] (0.1: Lowry et al.'s common choice for small shifts).
    ridge_alpha : float
        Ridge penalty of the normal-behaviour regression on standardised inputs, >= 0
        (1e-3) [choice].
    variance : float
        Share of the commissioning variance the PCA keeps, in (0, 1) (0.95) [choice].
    quantile : float
        Quantile of commissioning's T² and SPE each is scaled by, in (0.5, 1) (0.999).
    """

    lam: float = field(default=0.1, metadata=allowed(0.0, 1.0, lo_open=True))
    ridge_alpha: float = field(default=1e-3, metadata=allowed(0.0, 1e6))
    variance: float = field(default=0.95, metadata=allowed(0.0, 1.0, lo_open=True,
                                                           hi_open=True))
    quantile: float = field(default=0.999, metadata=allowed(0.5, 1.0, lo_open=True,
                                                            hi_open=True))


def _check(x: np.ndarray, duty: np.ndarray, temp: np.ndarray | None
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shapes (W, F), (W,), (W,) as float arrays (temperature NaN where missing)."""
    x = np.asarray(x, dtype=float)
    duty = np.asarray(duty)
    t = np.full(len(x), np.nan) if temp is None else np.asarray(temp, dtype=float)
    if x.ndim != 2 or duty.shape != (len(x),) or t.shape != (len(x),):
        raise ValueError(f"features (W, F), duty (W,) and temperature (W,) must agree, got "
                         f"{x.shape}, {duty.shape}, {t.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("features must be finite")
    return x, duty, t


class RegressionMEWMA:
    """Normal-behaviour regression and a MEWMA chart of its residuals (module docstring).

    Parameters
    ----------
    cfg : BaselineConfig, optional
    """

    def __init__(self, cfg: BaselineConfig | None = None) -> None:
        self.cfg = cfg or BaselineConfig()

    def _design(self, duty: np.ndarray, temp: np.ndarray) -> np.ndarray:
        """[one-hot duty point] ⊗ [1, ΔT, ΔT²], ΔT the reading about commissioning's mean
        over its spread (a missing reading at the mean), shape (W, 3 D)."""
        dt = np.where(np.isfinite(temp), (temp - self.t_mean_) / self.t_scale_, 0.0)
        one = (duty[:, None] == self.duties_[None, :]).astype(float)  # (W, D)
        return np.concatenate([one, one * dt[:, None], one * dt[:, None] ** 2], axis=1)

    def fit(self, x: np.ndarray, duty: np.ndarray, temp: np.ndarray | None = None
            ) -> RegressionMEWMA:
        """Commission on healthy windows.

        Parameters
        ----------
        x : ndarray, shape (W, F)
            Health features of the commissioning windows.
        duty : ndarray, shape (W,)
            Each window's duty point (any hashable label).
        temp : ndarray, shape (W,), optional
            The temperature reading [°C] (NaN where missing).

        Returns
        -------
        RegressionMEWMA
            Fitted.
        """
        from sklearn.covariance import LedoitWolf
        from sklearn.linear_model import Ridge

        x, duty, temp = _check(x, duty, temp)
        ok = np.isfinite(temp)
        self.t_mean_ = float(temp[ok].mean()) if ok.any() else 0.0
        self.t_scale_ = float(temp[ok].std()) if ok.sum() > 1 and temp[ok].std() > 0 else 1.0
        self.duties_ = np.unique(duty)
        self.reg_ = Ridge(alpha=self.cfg.ridge_alpha, fit_intercept=False).fit(
            self._design(duty, temp), x)
        r = x - self.reg_.predict(self._design(duty, temp))
        cov = LedoitWolf().fit(r).covariance_
        lam = self.cfg.lam
        self.prec_ = np.linalg.inv(cov * lam / (2.0 - lam))
        return self

    def statistic(self, x: np.ndarray, duty: np.ndarray, temp: np.ndarray | None = None
                  ) -> np.ndarray:
        """The MEWMA statistic of windows in time order (the EWMA starts at 0 at the first).

        Parameters
        ----------
        x, duty, temp
            As :meth:`fit`; a duty point commissioning never saw reads as none of its.

        Returns
        -------
        ndarray, shape (W,)
        """
        x, duty, temp = _check(x, duty, temp)
        r = x - self.reg_.predict(self._design(duty, temp))
        z, lam = np.zeros(r.shape[1]), self.cfg.lam
        out = np.empty(len(r))
        for k in range(len(r)):  # a recursion over the windows
            z = lam * r[k] + (1.0 - lam) * z
            out[k] = z @ self.prec_ @ z
        return out


class PCAChart:
    """Hotelling's T² and the SPE of a PCA of the standardised features (module
    docstring).

    Parameters
    ----------
    cfg : BaselineConfig, optional
    """

    def __init__(self, cfg: BaselineConfig | None = None) -> None:
        self.cfg = cfg or BaselineConfig()

    def _standard(self, x: np.ndarray, duty: np.ndarray) -> np.ndarray:
        """Each feature about its duty point's commissioning mean over its sd (a duty point
        never seen: the overall ones)."""
        out = (x - self.mean_) / self.sd_
        for d, (m, s) in self.by_duty_.items():
            rows = duty == d
            out[rows] = (x[rows] - m) / s
        return out

    def fit(self, x: np.ndarray, duty: np.ndarray, temp: np.ndarray | None = None
            ) -> PCAChart:
        """Commission on healthy windows (``temp`` is not read: the PCA knows no operating
        variable but the duty point).

        Returns
        -------
        PCAChart
            Fitted.
        """
        from sklearn.decomposition import PCA

        x, duty, _ = _check(x, duty, temp)
        self.mean_, self.sd_ = x.mean(axis=0), np.maximum(x.std(axis=0), 1e-12)
        self.by_duty_ = {d: (x[duty == d].mean(axis=0),
                             np.maximum(x[duty == d].std(axis=0), 1e-12))
                         for d in np.unique(duty)}
        s = self._standard(x, duty)
        self.pca_ = PCA(n_components=self.cfg.variance, svd_solver="full").fit(s)
        t2, spe = self._parts(s)
        q = self.cfg.quantile
        self.t2_limit_, self.spe_limit_ = (float(np.quantile(v, q)) for v in (t2, spe))
        return self

    def _parts(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        scores = self.pca_.transform(s)
        t2 = np.sum(scores**2 / self.pca_.explained_variance_, axis=1)
        spe = np.sum((s - self.pca_.inverse_transform(scores)) ** 2, axis=1)
        return t2, spe

    def statistic(self, x: np.ndarray, duty: np.ndarray, temp: np.ndarray | None = None
                  ) -> np.ndarray:
        """max(T² / its limit, SPE / its limit) of each window, shape (W,)."""
        x, duty, _ = _check(x, duty, temp)
        t2, spe = self._parts(self._standard(x, duty))
        return np.maximum(t2 / self.t2_limit_, spe / max(self.spe_limit_, 1e-300))
