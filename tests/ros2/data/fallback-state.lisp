(state (robot Pippi) (laser Pippi) (sonar Pippi))
(goal (do-drive Pippi))
