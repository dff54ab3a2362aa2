"""
Ray budgets and certificates
============================

How many rays a reading needs and what the rays spent certify: the bounds
(:mod:`.bounds`, eqs. (15), (19), (23) of Baranoski et al. 2001, and the exact
binomial rule with its tables :mod:`.tables`), the rule objects (:mod:`.rules`), the
two-stage design (:mod:`.twostage`), Clopper–Pearson intervals (:mod:`.intervals`) and
the simultaneous bounds over a goniophotometer's bins (:mod:`.bins`), and the
stratified betting confidence sequences of weighted sums (:mod:`.betting`).
"""
