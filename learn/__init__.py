"""Learning affordances: effect categories, relevant features, predictors (imports features only).

Per behaviour, as the thesis's chapters 3, 8 and 10 describe:

1. :class:`EffectCategories` groups the effects ``after - before`` into categories
   (channel-wise :class:`XMeans`, Cartesian product, pruning by frequency or predictability);
2. :class:`FeatureRelevance` ranks the object features (ReliefF, forward selection,
   backward elimination);
3. :class:`AffordancePredictor` maps the relevant features and the behaviour parameters to
   calibrated probabilities over the categories;
4. :func:`evaluate_predictions` and :func:`baseline_scores` measure it on held-out data.
"""

from afford.learn.effects import EffectCategories
from afford.learn.evaluate import baseline_scores, evaluate_predictions
from afford.learn.predictors import TRUSTED_TYPES, AffordancePredictor
from afford.learn.relevance import FeatureRelevance, backward_elimination, feature_groups, forward_selection, relieff
from afford.learn.xmeans import XMeans, bic_score

__all__ = [
    "AffordancePredictor",
    "EffectCategories",
    "FeatureRelevance",
    "TRUSTED_TYPES",
    "XMeans",
    "backward_elimination",
    "baseline_scores",
    "bic_score",
    "evaluate_predictions",
    "feature_groups",
    "forward_selection",
    "relieff",
]
