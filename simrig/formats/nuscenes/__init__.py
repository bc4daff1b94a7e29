"""nuScenes: the devkit's tables as ground truth (:mod:`.ground_truth`), tracking-results JSON (:mod:`.tracks`),
both written so the devkit's ``TrackingEval`` runs on them (:mod:`.writer`), sample tokens (:mod:`.samples`)
and the devkit's gap interpolation (:mod:`.interpolation`)."""
