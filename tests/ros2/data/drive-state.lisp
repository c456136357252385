(state (robot Pippi) (laser Pippi))
(goal (do-drive Pippi))
