"""oddball: a P300 brain-computer interface in Rust, from Python.

Drop-in scikit-learn / pyRiemann estimators computed by oddball's Rust decoders
(``oddball.estimation.XdawnCovariances``, ``oddball.tangentspace.TangentSpace``,
``oddball.classification.MDM``, ``oddball.spatialfilters.Xdawn``,
``oddball.lda.LinearDiscriminantAnalysis``, ``oddball.lda.ToeplitzLDA``), oddball's presets as
scikit-learn pipelines (``oddball.pipelines.make``), its readers (``oddball.read_raw``), and the online decoder behind your own stimulus loop
(``oddball.online.OnlineDecoder``, ``oddball decode``'s engine).
"""
from . import classification, estimation, lda, online, pipelines, spatialfilters, tangentspace
from ._oddball import __version__
from .io import Raw, read_raw

__all__ = [
    "Raw",
    "__version__",
    "classification",
    "estimation",
    "lda",
    "online",
    "pipelines",
    "read_raw",
    "spatialfilters",
    "tangentspace",
]
