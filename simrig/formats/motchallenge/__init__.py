"""MOTChallenge: ground truth (:mod:`.ground_truth`), a tracker's text files (:mod:`.tracks`) and the folders
TrackEval's ``MotChallenge2DBox`` reads (:mod:`.writer`)."""
