"""The detector model: per camera, what an imperfect detector reports and why (see :mod:`.model`)."""
