"""Board model of the Sipeed Maix Dock (Kendryte K210) on Unicorn."""
