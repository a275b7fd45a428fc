"""Learning from demonstration: demonstration data and rollouts of learned vector fields."""
