"""Everything a run records goes into one rerun recording (``.rrd``): metrics, episodes, layout.

- ``logger.RerunLogger``: TorchRL ``Logger`` over a ``rerun.RecordingStream`` (scalars, histograms,
  hyper-parameters); owns the file and closes it cleanly.
- ``episode.EpisodeTrack``: records episodes of one juggling env (a ``JuggleEnv``'s, or one env of
  a ``JuggleBatch``) in 3D on a ``sim_time`` timeline, with the ball-height plot and a marker per
  counted throw; ``episode.EpisodeRecorder``: a Gymnasium wrapper that records with it;
  ``episode.record_episode``: one recorded episode of a policy.
- ``geometry``: the scene's primitive geoms as rerun archetypes, and body poses per frame.
- ``blueprint``: the layout each kind of recording opens with (episode, training, searches).

Entity paths: ``world/...`` (scene, the ball at ``world/ball``), ``plots/...`` (ball height),
``train/...``, ``eval/...``, ``dps/...`` (metrics), ``hparams`` and ``summary`` (text). The
episode recorder and the blueprint do not import torch; ``logger`` does (through TorchRL).
"""
