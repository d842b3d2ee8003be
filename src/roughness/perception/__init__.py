"""Perception experiments: triplet trials, their embedding (Wills et al. 2009), and the fit of V to it.

Modules: ``trials`` (the trials file), ``stimuli`` (the stimuli table), ``embed`` (the SDP),
``crossval`` and ``bootstrap`` (choosing lam, intervals), ``parallel`` (solves over processes),
``analysis`` (the embed pipeline and its files), ``observer`` (a simulated observer), ``design``
(balanced trial lists), ``values`` (V of stimuli, FEM results cached by content), ``fit`` (V against
the embedding, re-fit over the pair sampling and force), ``plots`` (the paper's Figs. 9, 10, 17, 18).
cvxpy is needed only by ``embed`` and what uses it: ``pip install 'roughness[perception]'``.
"""
