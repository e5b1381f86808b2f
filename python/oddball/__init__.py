"""oddball: a P300 brain-computer interface in Rust, from Python.

Drop-in scikit-learn / pyRiemann estimators computed by oddball's Rust decoders
(``oddball.estimation.XdawnCovariances``, ``oddball.tangentspace.TangentSpace``,
``oddball.classification.MDM``, ``oddball.spatialfilters.Xdawn``,
``oddball.lda.LinearDiscriminantAnalysis``, ``oddball.lda.ToeplitzLDA``), decoders that learn
while used (``oddball.lda.AdaptiveLDA.partial_fit``; ``oddball.unsupervised.UnsupervisedDecoder``,
fitted without labels), oddball's presets as scikit-learn pipelines (``oddball.pipelines.make``),
its readers (``oddball.read_raw``, ``oddball.read_epochs``), and the online decoder behind your
own stimulus loop (``oddball.online.OnlineDecoder``, ``oddball decode``'s engine).
"""
from . import classification, estimation, lda, online, pipelines, spatialfilters, tangentspace, unsupervised
from ._oddball import __version__
from .io import Epochs, Raw, read_epochs, read_raw

__all__ = [
    "Epochs",
    "Raw",
    "__version__",
    "classification",
    "estimation",
    "lda",
    "online",
    "pipelines",
    "read_epochs",
    "read_raw",
    "spatialfilters",
    "tangentspace",
    "unsupervised",
]
