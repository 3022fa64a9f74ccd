"""Training of the GO1's learned controller (PPO in torch, terrain curriculum).

Run ``python -m havln_mj.train_go1 --config configs/go1_learned.json --out RUN``; the run
folder's ``policy.npz`` is what :func:`~havln_mj.robot.go1.learned.policy.load_policy` reads. Needs
the ``agents`` extra (torch) and matplotlib for the plot.
"""
